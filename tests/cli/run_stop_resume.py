#!/usr/bin/env python3
"""Graceful stop of `csgtile run`: SIGTERM while a job runs → that job finishes (it fits the
grace period of 600 s, even under sanitizers; tests/cli/sigterm_grace.py covers the job
that does not and is released), nothing more
is claimed, exit 0 with the count left; running the same config again resumes and completes
the run with every job done once (the queue keeps the state); `csgtile status` shows both. Jobs are fuses of the timber
gate (`csgtile synth gate` truth, 229 primitives, a few seconds each).
Usage: run_stop_resume.py CSGTILE WORKDIR"""
import json
import os
import shutil
import signal
import sqlite3
import subprocess
import sys
import time

binary, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
subprocess.run([binary, "synth", "gate", "--points", "2000", "--out", f"{work}/scan.las",
                "--truth", f"{work}/truth.json"], check=True, capture_output=True)
scene = json.load(open(f"{work}/truth.json"))
inputs = []
for k in range(3):
    scene["name"], scene["op"] = f"gate-{k}", "fuse"
    for prim in scene["primitives"]:  # copies 200 m apart: no relations between them
        prim["placement"][0][3] += 200.0 if k else 0.0
    path = f"{work}/gate-{k}.json"
    json.dump(scene, open(path, "w"))
    inputs.append(path)
with open(f"{work}/run.yaml", "w") as f:
    f.write("run:\n  name: stopping\n  inputs:\n" + "".join(f"    - {p}\n" for p in inputs) +
            f"  output: {work}/out\nqueue:\n  grace_seconds: 600\nlog:\n  format: json\n")

p = subprocess.Popen([binary, "run", f"{work}/run.yaml", "--json"], stdout=subprocess.PIPE,
                     stderr=subprocess.PIPE, text=True)


def running_jobs():
    """Jobs the queue holds as running (0 before the queue exists)."""
    try:
        with sqlite3.connect(f"file:{work}/out/queue.sqlite?mode=ro", uri=True, timeout=5) as db:
            return db.execute("SELECT COUNT(*) FROM jobs WHERE state = 'running'").fetchone()[0]
    except sqlite3.Error:
        return 0


# Inside the first job: wait for the queue to say so (a fixed sleep raced the process's start
# under sanitizers on a loaded machine, and SIGTERM then came before its handler).
deadline = time.time() + 120
while running_jobs() == 0:
    assert p.poll() is None, (p.returncode, p.communicate())
    assert time.time() < deadline, "the run never started a job"
    time.sleep(0.05)
p.send_signal(signal.SIGTERM)
start = time.time()
out, err = p.communicate(timeout=120)
assert p.returncode == 0, (p.returncode, out, err)
summary = json.loads(out.strip().splitlines()[-1])
assert summary["stopped"] is True and summary["done"] >= 1 and summary["unfinished"] >= 1, summary
assert not os.path.exists(f"{work}/out/runs/stopping/manifest.json"), "a stopped run has no manifest"
print(f"stopped after {time.time() - start:.1f} s: {summary}")
status = json.loads(subprocess.run([binary, "status", f"{work}/run.yaml", "--json"], check=True,
                                   capture_output=True, text=True).stdout)
assert not status["finished"] and status["jobs"]["done"] == summary["done"], status
assert status["jobs"]["queued"] + status["jobs"]["retry"] == summary["unfinished"], status

again = subprocess.run([binary, "run", f"{work}/run.yaml", "--json"], capture_output=True, text=True)
assert again.returncode == 0, (again.returncode, again.stdout, again.stderr)
final = json.loads(again.stdout.strip().splitlines()[-1])
assert final["done"] == 3 and final["dead"] == 0, final
manifest = json.load(open(f"{work}/out/runs/stopping/manifest.json"))
assert len(manifest["jobs"]) == 3, manifest["jobs"]
status = json.loads(subprocess.run([binary, "status", f"{work}/run.yaml", "--json"], check=True,
                                   capture_output=True, text=True).stdout)
assert status["finished"] and status["jobs"]["done"] == 3 and status["dead"] == [], status
print("resumed:", final)
