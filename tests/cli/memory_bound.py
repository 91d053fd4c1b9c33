#!/usr/bin/env python3
"""A job's memory, recorded and bounded (queue.job_memory_mib): a city run over a synthetic
scan (`csgtile synth city-block`, 200 k points), first with a bound every job's process is
already over (1 MiB), then with none.
  * bounded: the fit job is stopped and dead with resource_limit and the bound named, it is
    not retried, the run still finishes (exit 3, jobs_failed) and its manifest lists the dead
    job with that reason;
  * unbounded: every job of timings.json carries its peak resident memory (peak_rss_mib, a
    plausible number of MiB) and the report's timings.js names the job of the highest peak.
A job that ends before the work loop's first look (50 ms) is not stopped: the fit of 200 k
points takes far longer. Usage: memory_bound.py CSGTILE WORK_DIR
"""
import json
import os
import shutil
import subprocess
import sys

binary, work = sys.argv[1:3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
scan = f"{work}/block.las"
subprocess.run([binary, "synth", "city-block", "--out", scan, "--truth", f"{work}/truth.json",
                "--points", "200000"], check=True, capture_output=True)


def run(name, bound):
    config = f"{work}/{name}.yaml"
    with open(config, "w") as f:
        f.write(f"run:\n  name: {name}\n  inputs:\n    - {scan}\n  output: {work}/{name}\n"
                f"queue:\n  job_memory_mib: {bound}\n  max_attempts: 3\nlog:\n  level: warn\n")
    p = subprocess.run([binary, "run", config, "--json"], capture_output=True, text=True)
    return p, f"{work}/{name}/runs/{name}"


p, rundir = run("bounded", 1)
assert p.returncode == 3, f"bounded: exit {p.returncode}\n{p.stdout}\n{p.stderr}"
manifest = json.load(open(f"{rundir}/manifest.json"))
dead = manifest["dead"]
assert dead, manifest
fits = [d for d in dead if d["key"].startswith("fit:")]
assert fits, dead
for d in fits:
    assert d["error"].startswith("resource_limit: "), d
    assert "queue.job_memory_mib = 1" in d["error"], d
    assert d["attempts"] == 1, ("not retried", d)

p, rundir = run("unbounded", 0)
assert p.returncode == 0, f"unbounded: exit {p.returncode}\n{p.stdout}\n{p.stderr}"
timings = json.load(open(f"{rundir}/timings.json"))["jobs"]
assert timings, "no job timings"
for t in timings:
    assert 5.0 < t["peak_rss_mib"] < 16384.0, t
script = open(f"{rundir}/report/timings.js").read()
top = max(timings, key=lambda t: t["peak_rss_mib"])
assert f'"job":"{top["key"]}"' in script.replace(" ", ""), script
print(json.dumps({"dead_by_bound": [d["key"] for d in fits],
                  "peak_rss_mib": {t["key"]: t["peak_rss_mib"] for t in timings}}))
