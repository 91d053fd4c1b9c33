#!/usr/bin/env python3
"""A building's time limit (issue #18 item 5, city.building_timeout_seconds): `csgtile run`
over ../shared/data/ams/ahn_2386_9702.las with a limit no fuse can meet (1 µs), then with the
default (60 s):
  * with the tiny limit the run ends without a dead job; every building of several parts is
    published as a Building of its LoD1.3 and LoD1.2 blocks alone ("lod_reached": "1.3"), its
    "lod22_failure" naming the limit; its cell's manifest counts it (objects_timed_out) and
    names it in its problems with the config key; a building of one part has no fuse to
    limit and keeps its LoD2.2; val3dity finds every published solid valid;
  * with the default limit no building reaches it: every building reaches LoD2.2.
The limit is checked between the Booleans' steps (kernel/interrupt.h), so the first check of
every fuse already finds it passed: the outcome does not depend on the machine's speed.
Prints the counts as JSON. Skips with a message when the shared data is absent; val3dity is
required when the data is present.
Usage: city_run_timeout.py CSGTILE SOURCE_DIR WORK_DIR
"""
import glob
import json
import os
import shutil
import subprocess
import sys

binary, source, work = sys.argv[1:4]
tile = os.path.join(source, "..", "shared", "data", "ams", "ahn_2386_9702.las")
val3dity = os.path.join(source, "..", "shared", "tools", "val3dity", "val3dity")
if not os.path.exists(tile):
    print(f"skip: shared data absent ({tile})")
    sys.exit(0)
if not os.path.exists(val3dity):
    sys.exit(f"val3dity is required beside the shared data: {val3dity} is missing")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def run(name, limit):
    config = f"{work}/{name}.yaml"
    with open(config, "w") as f:
        f.write(f"run:\n  name: {name}\n  inputs:\n    - {tile}\n  output: {work}/{name}\n"
                "  crs: EPSG:28992+5709\n" + (f"city:\n  building_timeout_seconds: {limit}\n"
                                              if limit is not None else "") +
                "log:\n  level: warn\n")
    p = subprocess.run([binary, "run", config, "--json"], capture_output=True, text=True)
    assert p.returncode == 0, f"{name}: exit {p.returncode}\n{p.stdout}\n{p.stderr}"
    rundir = f"{work}/{name}/runs/{name}"
    manifest = json.load(open(f"{rundir}/manifest.json"))
    assert manifest["dead"] == [], (name, manifest["dead"])
    out = {"buildings": 0, "lod22": 0, "blocks_only": 0, "timed_out": 0, "valid": 0,
           "features": 0, "problems": []}
    for cell in glob.glob(f"{rundir}/cells/*/manifest.json"):
        m = json.load(open(cell))
        out["timed_out"] += m["stats"]["objects_timed_out"]
        out["problems"] += m.get("problems", [])
    for seq in sorted(glob.glob(f"{rundir}/cells/*/model.city.jsonl")):
        with open(seq) as f:
            lines = f.readlines()[1:]
        for line in lines:
            for oid, o in json.loads(line)["CityObjects"].items():
                assert o["type"] == "Building", (name, oid, o["type"])
                a = o["attributes"]
                kinds = [(g["lod"], g["type"]) for g in o.get("geometry", [])]
                out["buildings"] += 1
                if a["lod_reached"] == "2.2":
                    assert kinds == [("2.2", "Solid"), ("1.3", "Solid"), ("1.2", "Solid")], \
                        (name, oid, kinds)
                    out["lod22"] += 1
                else:
                    # Its blocks (LoD1.3 by part, LoD1.2), fused on their own without a limit.
                    assert kinds == [("1.3", "Solid"), ("1.2", "Solid")], (name, oid, kinds)
                    assert a["lod_reached"] == "1.3", (name, oid, a["lod_reached"])
                    assert "time limit of" in a.get("lod22_failure", ""), (name, oid, a)
                    out["blocks_only"] += 1
        report = f"{seq}.val3dity.json"
        subprocess.run([val3dity, seq, "--report", report], capture_output=True, check=True)
        r = json.load(open(report))
        out["features"] += len(r["features"])
        out["valid"] += sum(1 for x in r["features"] if x["validity"])
    return out


tiny = run("tiny", "0.000001")
assert tiny["blocks_only"] >= 1, tiny
assert tiny["timed_out"] == tiny["blocks_only"], tiny
named = [p for p in tiny["problems"] if "city.building_timeout_seconds" in p]
assert len(named) == tiny["timed_out"], tiny["problems"]
assert tiny["valid"] == tiny["features"] > 0, tiny
default = run("default", None)
assert default["timed_out"] == 0 and default["blocks_only"] == 0, default
assert default["lod22"] == default["buildings"] == tiny["buildings"], (default, tiny)
assert default["valid"] == default["features"], default
for r in (tiny, default):
    del r["problems"]
print(json.dumps({"tiny_limit": tiny, "default_limit": default}))
