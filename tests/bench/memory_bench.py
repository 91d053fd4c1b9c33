#!/usr/bin/env python3
"""Peak memory of the two large jobs of issue #22 (item 6), each in a process of its own:
  * `csgtile fit` of synthetic airborne scans of a city block (`csgtile synth city-block`) of
    growing size, up to 5 M points: peak resident memory (the child's ru_maxrss) and bytes per
    point, and the growth between the two largest scans per added point;
  * the assembly of a synthetic city of 5 000 primitives (and 1 000), by
    build/tests/bench/assemble_bench (its own forked child per run).
Prints one JSON object. Usage: memory_bench.py BUILD_DIR WORK_DIR [--points N,N,...]
"""
import argparse
import json
import os
import shutil
import subprocess
import time

parser = argparse.ArgumentParser()
parser.add_argument("build")
parser.add_argument("work")
parser.add_argument("--points", default="1000000,2000000,5000000")
args = parser.parse_args()
binary = os.path.join(args.build, "csgtile")
shutil.rmtree(args.work, ignore_errors=True)
os.makedirs(args.work)


def peak_of(command):
    """Runs `command`; returns (seconds, peak resident MiB of that child)."""
    start = time.monotonic()
    child = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(child.pid, 0)
    seconds = time.monotonic() - start
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"{command[:2]} failed: {child.stderr.read().decode()[-2000:]}")
    return seconds, usage.ru_maxrss / 1024.0


fits = []
for n in [int(x) for x in args.points.split(",")]:
    scan = os.path.join(args.work, f"block_{n}.las")
    subprocess.run([binary, "synth", "city-block", "--points", str(n), "--out", scan, "--truth",
                    os.path.join(args.work, f"block_{n}.json")], check=True,
                   capture_output=True)
    seconds, mib = peak_of([binary, "fit", scan, "--out", os.path.join(args.work, f"fit_{n}.json")])
    fits.append({"points": n, "seconds": round(seconds, 2), "peak_rss_mib": round(mib, 1),
                 "bytes_per_point": round(mib * 1048576 / n, 1)})
growth = None
if len(fits) >= 2:
    a, b = fits[-2], fits[-1]
    growth = round((b["peak_rss_mib"] - a["peak_rss_mib"]) * 1048576 / (b["points"] - a["points"]), 1)

bench = os.path.join(args.build, "tests", "bench", "assemble_bench")
p = subprocess.run([bench, "--sizes", "1000,5000", "--all-pairs-max", "0"], check=True,
                   capture_output=True, text=True)
cells = [{"primitives": r["n"], "seconds": r["seconds"], "peak_rss_mib": r["peak_rss_mb"],
          "objects": r["objects"]}
         for r in json.loads(p.stdout)["runs"] if r["mode"] == "full"]
print(json.dumps({"benchmark": "memory", "fit": fits,
                  "fit_growth_bytes_per_added_point": growth, "assembly": cells}, indent=1))
