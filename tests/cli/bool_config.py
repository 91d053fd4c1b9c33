#!/usr/bin/env python3
"""`csgtile bool CASE --config C.yaml`: the config's kernel.linear_tolerance builds the
primitives and runs the Booleans, as the scene build job does (one path, geo/scene_model.h):
  * a unit cube and a 1 mm slab: valid at the default 1e-7, the slab degenerate at 1e-2;
  * the README's pavilion gives the same volume at 1e-6 as without a config;
  * a tolerance out of range is a config error (exit 78) naming the key and its line;
  * a run's build job at 1e-2 fails the slab by name, as `csgtile bool` does.
Usage: bool_config.py CSGTILE SOURCE_DIR WORKDIR"""
import json
import os
import shutil
import subprocess
import sys

binary, source, work = sys.argv[1], sys.argv[2], sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def placement(x):
    return [[1, 0, 0, x], [0, 1, 0, 0], [0, 0, 1, 0]]


# A unit cube and a 1 mm slab beside it: a solid at the default 1e-7, degenerate at 1e-2.
thin = f"{work}/thin_slab.json"
with open(thin, "w") as f:
    json.dump({"name": "thin-slab", "op": "fuse",
               "primitives": [{"id": "cube", "type": "box", "size": [1, 1, 1],
                               "placement": placement(0)},
                              {"id": "slab", "type": "box", "size": [0.001, 1, 1],
                               "placement": placement(2)}]}, f)


def config(tolerance):
    path = f"{work}/tolerance_{tolerance}.yaml"
    with open(path, "w") as f:
        f.write(f"kernel:\n  linear_tolerance: {tolerance}\n")
    return path


def run_bool(case, *extra):
    p = subprocess.run([binary, "bool", case, "--json", *extra], capture_output=True, text=True,
                       timeout=120)
    return p.returncode, p.stdout, p.stderr


figures = {}
code, out, err = run_bool(thin)
assert code == 0, (code, out, err)
default = json.loads(out)
assert default["valid"] and default["topology"]["solids"] == 2, default
assert abs(default["volume"] - 1.001) < 1e-12, default
code, out, err = run_bool(thin, "--config", config("1.0e-2"))
coarse = json.loads(out)
assert code != 0 and not coarse["valid"], (code, out, err)
assert "primitives[1]" in (coarse["error"] or "") or "slab" in (coarse["error"] or ""), coarse
figures["thin_slab"] = {"1e-7": "valid", "1e-2": coarse["error"]}

pavilion = f"{source}/config/examples/scenes/pavilion_fused.json"
code, out, err = run_bool(pavilion)
assert code == 0, (code, err)
plain = json.loads(out)
code, out, err = run_bool(pavilion, "--config", config("1.0e-6"))
assert code == 0, (code, err)
configured = json.loads(out)
assert abs(plain["volume"] - configured["volume"]) <= 1e-9 * plain["volume"], (plain, configured)

code, out, err = run_bool(pavilion, "--config", config("0.5"))
assert code == 78, (code, out, err)
assert "kernel.linear_tolerance" in err and ":2" in err, err

# The build job of a run with the same config fails the slab by name too.
run_config = f"{work}/run.yaml"
with open(run_config, "w") as f:
    f.write(f"run:\n  name: thin{os.getpid()}\n  inputs:\n    - {thin}\n  output: {work}/out\n"
            "kernel:\n  linear_tolerance: 1.0e-2\nlog:\n  format: json\n")
p = subprocess.run([binary, "run", run_config, "--json"], capture_output=True, text=True,
                   timeout=300)
summary = json.loads(p.stdout.strip().splitlines()[-1])
manifest = json.load(open(summary["manifest"]))
assert [d["key"].split(":")[0] for d in manifest["dead"]] == ["build"], manifest["dead"]
assert "primitives[1] (box)" in manifest["dead"][0]["error"], manifest["dead"]
figures["build_job"] = manifest["dead"][0]["error"]
print(json.dumps(figures))
