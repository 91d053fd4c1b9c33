#!/usr/bin/env python3
"""Peak memory of the two large jobs of issue #22 (item 6), each in a process of its own:
  * `csgtile fit` of synthetic airborne scans of a city block (`csgtile synth city-block`) of
    growing size, up to 5 M points: peak resident memory (the child's ru_maxrss) and bytes per
    point, and the growth between the two largest scans per added point;
  * a city run (`csgtile run`, one thread, 50 m cells, 20 m halo) over the largest scan as one
    tile and with city.split_points (--split-points, default a quarter of the scan): every fit
    job's peak (timings.json's peak_rss_mib: the worker's resident memory while the job ran),
    the points its fit read and the fit's seconds — a tile fitted in blocks of cells holds a
    block and its halo rather than the tile;
  * the assembly of a synthetic city of 5 000 primitives (and 1 000), by
    build/tests/bench/assemble_bench (its own forked child per run).
Prints one JSON object. Usage: memory_bench.py BUILD_DIR WORK_DIR [--points N,N,...]
                              [--split-points N]
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
parser.add_argument("--split-points", type=int, default=0)
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



def city_run(scan, split):
    """A city run over `scan` with city.split_points `split`: its fit jobs' peaks and points."""
    name = f"run_split{split}"
    config = os.path.join(args.work, name + ".yaml")
    with open(config, "w") as f:
        f.write(f"run:\n  name: {name}\n  inputs:\n    - {scan}\n"
                f"  output: {os.path.join(args.work, name)}\n  threads: 1\n"
                f"city:\n  cell_size: 50\n  halo: 20\n  split_points: {split}\n"
                "log:\n  level: warn\n")
    seconds, _ = peak_of([binary, "run", config, "--json"])
    rundir = os.path.join(args.work, name, "runs", name)
    timings = json.load(open(os.path.join(rundir, "timings.json")))["jobs"]
    manifest = json.load(open(os.path.join(rundir, "manifest.json")))
    points = {j["key"]: j["result"].get("points") for j in manifest["jobs"]
              if j["key"].startswith("fit:")}
    fits = [{"job": j["key"].split(":", 2)[2], "peak_rss_mib": j.get("peak_rss_mib"),
             "points_read": points.get(j["key"]),
             "fit_seconds": round(j["stages"].get("fit", 0.0), 2)}
            for j in timings if j["key"].startswith("fit:")]
    return {"split_points": split, "run_seconds": round(seconds, 2),
            "objects": manifest["totals"].get("objects"),
            "max_fit_peak_rss_mib": max(f["peak_rss_mib"] or 0 for f in fits), "fit_jobs": fits}


largest = fits[-1]["points"]
scan = os.path.join(args.work, f"block_{largest}.las")
split = args.split_points or largest // 4
runs = [city_run(scan, 0), city_run(scan, split)]

bench = os.path.join(args.build, "tests", "bench", "assemble_bench")
p = subprocess.run([bench, "--sizes", "1000,5000", "--all-pairs-max", "0"], check=True,
                   capture_output=True, text=True)
cells = [{"primitives": r["n"], "seconds": r["seconds"], "peak_rss_mib": r["peak_rss_mb"],
          "objects": r["objects"]}
         for r in json.loads(p.stdout)["runs"] if r["mode"] == "full"]
print(json.dumps({"benchmark": "memory", "fit": fits,
                  "fit_growth_bytes_per_added_point": growth, "city_runs": runs,
                  "assembly": cells}, indent=1))
