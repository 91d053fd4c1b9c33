#!/usr/bin/env python3
"""`csgtile enqueue` then two `csgtile worker --exit-when-idle` processes sharing one queue:
every job runs once (no job done twice, none lost), both workers exit 0, the run is
published (manifest with every job), `csgtile status` shows it finished, and enqueueing
again adds nothing.
Usage: enqueue_two_workers.py CSGTILE WORKDIR"""
import json
import os
import shutil
import subprocess
import sys

binary, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
subprocess.run([binary, "synth", "gate", "--points", "2000", "--out", f"{work}/scan.las",
                "--truth", f"{work}/truth.json"], check=True, capture_output=True)
scene = json.load(open(f"{work}/truth.json"))
prims = scene["primitives"]
inputs = []
for k in range(6):  # six jobs: a slice of the gate each, fused
    part = dict(scene, name=f"part-{k}", op="fuse", primitives=prims[k * 30:(k + 1) * 30])
    path = f"{work}/part-{k}.json"
    json.dump(part, open(path, "w"))
    inputs.append(path)
config = f"{work}/run.yaml"
with open(config, "w") as f:
    f.write("run:\n  name: shared\n  inputs:\n" + "".join(f"    - {p}\n" for p in inputs) +
            f"  output: {work}/out\nlog:\n  format: json\n")


def cli(*args):
    p = subprocess.run([binary, *args], capture_output=True, text=True)
    assert p.returncode == 0, (args, p.returncode, p.stdout, p.stderr)
    return json.loads(p.stdout.strip().splitlines()[-1])


assert cli("enqueue", config, "--json")["added"] == 6
workers = [subprocess.Popen([binary, "worker", config, "--exit-when-idle", "--json"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(2)]
outs = [w.communicate(timeout=300) for w in workers]
for w, (out, err) in zip(workers, outs):
    assert w.returncode == 0, (w.returncode, out, err)
    summary = json.loads(out.strip().splitlines()[-1])
    assert summary["done"] == 6 and summary["unfinished"] == 0, summary
# Each job was done by exactly one worker: one "done" log line per job over both workers.
done_lines = [json.loads(line) for _, err in outs for line in err.splitlines()
              if '"component":"job"' in line and '"message":"done"' in line]
keys = sorted(line["job"] for line in done_lines)
assert keys == sorted(set(keys)) and len(keys) == 6, keys
manifest = json.load(open(f"{work}/out/runs/shared/manifest.json"))
assert len(manifest["jobs"]) == 6 and manifest["dead"] == [], manifest["dead"]
status = cli("status", config, "--json")
assert status["finished"] and status["jobs"]["done"] == 6, status
assert cli("enqueue", config, "--json")["added"] == 0
print("ok: 6 jobs over 2 workers,", [sum(1 for _, e in [o] for l in e.splitlines() if '"message":"done"' in l) for o in outs])
