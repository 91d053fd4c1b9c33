#!/usr/bin/env python3
"""`csgtile run CONFIG --index N` (the Kubernetes Indexed Job form): each index runs exactly
input N of run.inputs as run <name>-<N> on a private queue, its manifest naming that one
job; two indexes never share a queue; an index outside the list is a usage error (exit 64)
naming the range; running an index again publishes the same manifest bytes.
Usage: run_index.py CSGTILE SOURCE_DIR WORKDIR"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

binary, source, work = sys.argv[1], sys.argv[2], sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
scenes = [f"{source}/config/examples/scenes/{n}" for n in
          ("pavilion.json", "courtyard_block.json", "pavilion_fused.json")]
name = f"indexed{os.getpid()}"  # the private queue lives in the temporary directory
config = f"{work}/run.yaml"
with open(config, "w") as f:
    f.write(f"run:\n  name: {name}\n  inputs:\n" + "".join(f"    - {s}\n" for s in scenes) +
            f"  output: {work}/out\nlog:\n  format: json\n")
try:
    manifests = {}
    for n in (2, 0, 2):
        p = subprocess.run([binary, "run", config, "--index", str(n), "--json"],
                           capture_output=True, text=True, timeout=300)
        assert p.returncode == 0, (n, p.returncode, p.stdout, p.stderr[-2000:])
        summary = json.loads(p.stdout.strip().splitlines()[-1])
        assert summary["run"] == f"{name}-{n}" and summary["done"] == 1, summary
        data = open(f"{work}/out/runs/{name}-{n}/manifest.json", "rb").read()
        jobs = json.loads(data)["jobs"]
        assert [j["result"]["input"] for j in jobs] == [scenes[n]], jobs
        if n in manifests:
            assert manifests[n] == data, "the same index publishes the same bytes"
        manifests[n] = data
    assert not os.path.exists(f"{work}/out/queue.sqlite"), "no shared queue"
    p = subprocess.run([binary, "run", config, "--index", "3"], capture_output=True, text=True)
    assert p.returncode == 64 and "outside run.inputs (3 input(s): 0..2)" in p.stderr, (p.returncode, p.stderr)
    print("ok: indexes 0 and 2 ran their own input; index 3 refused")
finally:
    for n in range(3):
        q = os.path.join(tempfile.gettempdir(), f"csgtile-{name}-{n}.sqlite")
        for suffix in ("", "-wal", "-shm"):
            if os.path.exists(q + suffix):
                os.remove(q + suffix)
