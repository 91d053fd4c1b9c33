#!/usr/bin/env python3
"""SIGTERM storm (issue #8): 100 SIGTERMs at random moments to `csgtile worker` processes (two
at a time) on one SQLite queue of short jobs. Every worker must exit 0 within the grace
period after its SIGTERM (here 10 s: the running job finishes, nothing more is claimed), no
job may be left running, and a final worker completes the run with every job done once.
Prints one JSON line of figures.
Usage: sigterm_storm.py CSGTILE WORKDIR [SIGNALS]"""
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from worker_jobs import write_jobs  # noqa: E402

binary, work = sys.argv[1], sys.argv[2]
signals = int(sys.argv[3]) if len(sys.argv) > 3 else 100
grace = 10.0
rng = random.Random(11)
shutil.rmtree(work, ignore_errors=True)
# ~0.5 s each (40 posts): the storm ends while jobs are still queued, so the SIGTERMs land on
# workers in their jobs and idle polls, not on the run's publication (8 posts ended all 400
# jobs mid-storm once the Booleans got faster).
inputs = write_jobs(f"{work}/scenes", 400, posts=40)
config = f"{work}/run.yaml"
with open(config, "w") as f:
    f.write("run:\n  name: storm\n  inputs:\n" + "".join(f"    - {p}\n" for p in inputs) +
            f"  output: {work}/out\nqueue:\n  lease_seconds: 30\nlog:\n  format: json\n")
p = subprocess.run([binary, "enqueue", config, "--json"], capture_output=True, text=True)
assert p.returncode == 0, p.stderr


def status():
    p = subprocess.run([binary, "status", config, "--json"], capture_output=True, text=True)
    assert p.returncode in (0, 3), (p.returncode, p.stderr)
    return json.loads(p.stdout.strip().splitlines()[-1])


spawned = [0]


def spawn():
    spawned[0] += 1
    log = open(f"{work}/worker-{spawned[0]}.log", "w+")
    p = subprocess.Popen([binary, "worker", config, "--json"], stdout=subprocess.DEVNULL, stderr=log)
    p.log = log
    return p


def started(w, timeout=30.0):
    """Waits until the worker has logged (it is in its work loop). A signal during the first
    ~0.2 s of a process — the dynamic loader relocating PCL and OpenVDB, before main — gets the
    default action; from main on, csgtile holds it until its handlers are installed."""
    end = time.time() + timeout
    while time.time() < end:
        if os.path.getsize(w.log.name) > 0 or w.poll() is not None:
            return
        time.sleep(0.02)


slowest = 0.0
sent = 0
workers = [spawn(), spawn()]
while sent < signals:
    i = rng.randrange(2)
    w = workers[i]
    started(w)
    time.sleep(rng.uniform(0.0, 0.3))
    w.send_signal(signal.SIGTERM)
    sent += 1
    t0 = time.time()
    try:
        code = w.wait(timeout=grace)
    except subprocess.TimeoutExpired:
        w.kill()
        sys.exit(f"a worker did not exit within {grace} s of SIGTERM #{sent}")
    slowest = max(slowest, time.time() - t0)
    assert code == 0, f"worker exited {code} after SIGTERM #{sent}"
    workers[i] = spawn()
for w in workers:
    started(w)
    w.send_signal(signal.SIGTERM)
    code = w.wait(timeout=grace)
    assert code == 0, f"worker exited {code} after the last SIGTERM"
left = status()
assert left["jobs"]["running"] == 0, ("a job left running", left["jobs"])
done_during_storm = left["jobs"]["done"]
p = subprocess.run([binary, "worker", config, "--exit-when-idle", "--json"], capture_output=True,
                   text=True, timeout=600)
assert p.returncode == 0, (p.returncode, p.stderr[-2000:])
final = status()
assert final["finished"] and final["jobs"]["done"] == 400 and final["jobs"]["dead"] == 0, final
manifest = json.load(open(f"{work}/out/runs/storm/manifest.json"))
keys = [j["key"] for j in manifest["jobs"]]
assert len(keys) == 400 and len(set(keys)) == 400
print(json.dumps({"sigterms": sent, "slowest_exit_seconds": round(slowest, 2),
                  "done_during_storm": done_during_storm, "left_running": 0, "done": 400}))
