#!/usr/bin/env python3
"""Inputs and run.crs are checked before any job is made (issue #19 item 5):
  * a missing input directory, an empty input directory and a run.crs that names no CRS are
    each a problem of `validate-config` with its key path and line, and `csgtile run` refuses
    the config with exit 78 (config_invalid) before making a queue;
  * `validate-config --no-input-check` accepts a config written for another machine;
  * a truncated tile's dead job names the file once.
Usage: inputs_checked.py CSGTILE WORKDIR"""
import json
import os
import shutil
import subprocess
import sys

binary, work = sys.argv[1:3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(f"{work}/empty")


def cli(*args):
    return subprocess.run([binary, *args], capture_output=True, text=True)


def config(name, inputs, crs=""):
    path = f"{work}/{name}.yaml"
    with open(path, "w") as f:
        f.write(f"run:\n  name: {name}\n  inputs:\n" + "".join(f"    - {i}\n" for i in inputs) +
                f"  output: {work}/{name}\n" + (f"  crs: {crs}\n" if crs else ""))
    return path


cases = [
    ("missing", [f"{work}/nothere/"], "", "run.inputs[0]", 4, "no such file or directory"),
    ("empty", [f"{work}/empty"], "", "run.inputs[0]", 4, "holds no LIDAR tile"),
    ("badcrs", [f"{work}/empty"], "EPSG:12345678", "run.crs", 6, "not a CRS"),
]
for name, inputs, crs, path, line, text in cases:
    cfg = config(name, inputs, crs)
    p = cli("validate-config", cfg, "--json")
    assert p.returncode == 78, (name, p.returncode, p.stdout, p.stderr)
    problems = json.loads(p.stdout)["problems"]
    assert any(q["path"] == path and q["line"] == line and text in q["message"] for q in problems), \
        (name, problems)
    p = cli("run", cfg, "--json")
    assert p.returncode == 78, (name, p.returncode, p.stderr)
    assert f"{path}" in p.stderr and text in p.stderr, (name, p.stderr)
    assert not os.path.exists(f"{work}/{name}/queue.sqlite"), f"{name}: a queue was made"

p = cli("validate-config", "--no-input-check", config("elsewhere", ["/data/tiles/"]))
assert p.returncode == 0 and "valid" in p.stdout, (p.returncode, p.stdout, p.stderr)

# A truncated tile: dead, its reason naming the file once.
with open(f"{work}/cut.las", "wb") as f:
    real = sys.argv[3] if len(sys.argv) > 3 and os.path.exists(sys.argv[3]) else None
    f.write(open(real, "rb").read()[:30000] if real else b"LASF" + bytes(300))
p = cli("run", config("cut", [f"{work}/cut.las"]), "--json")
assert p.returncode == 3, (p.returncode, p.stdout, p.stderr)
dead = json.load(open(f"{work}/cut/runs/cut/manifest.json"))["dead"]
assert len(dead) == 1 and dead[0]["error"].count("cut.las") == 1, dead
print(json.dumps({"checked": len(cases) + 2}))
