#!/usr/bin/env python3
"""`csgtile assemble` end to end: the truth scene of `csgtile synth city-block`, assembled
whole and cut into cells with a halo, gives the same objects (ids, primitives, volumes) and
total volume; the outputs exist; without the OpenVDB module the same objects, unculled, with
the reason; bad input exits non-zero with a named reason.
Usage: assemble_cells.py CSGTILE WORKDIR"""
import json
import os
import shutil
import subprocess
import sys

binary, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def run(*args, ok=True):
    p = subprocess.run([binary, *args], capture_output=True, text=True)
    if ok and p.returncode != 0:
        sys.exit(f"{' '.join(args)} failed ({p.returncode}):\n{p.stdout}{p.stderr}")
    return p


run("synth", "city-block", "--points", "2000", "--seed", "3", "--out", f"{work}/scan.las",
    "--truth", f"{work}/truth.json")
whole = json.loads(run("assemble", f"{work}/truth.json", "--out", f"{work}/whole", "--json").stdout)
stats = whole["statistics"]
assert stats["objects"] > 0 and stats["interacting_pairs"] > 0, stats
assert os.path.getsize(f"{work}/whole/model.csgt") > 0
body = json.load(open(f"{work}/whole/assembly.json"))
# An object whose fuse fails is kept unfused with its reason, never silently.
failed = [o for o in body["objects"] if not o["fused"]]
assert len(failed) == stats["objects_failed"], stats
assert all(o["error"] and any(o["id"] in p for p in body["problems"]) for o in failed), failed
objects = {o["id"]: (o["primitives"], o["volume"]) for o in body["objects"]}
assert len(objects) == stats["objects"]
extent = max(max(o["bbox"][3] - o["bbox"][0], o["bbox"][4] - o["bbox"][1]) for o in body["objects"])

# Without the OpenVDB module (libcsgtile_vdb.so) nothing is culled: every candidate pair is
# tested exactly, the objects are the same, and the assembly says why it did not cull. A ball in
# a ring's hole: their boxes overlap, their shells do not, so the culling decides the pair.
with open(f"{work}/ring.json", "w") as f:
    json.dump({"name": "ring-and-ball",
               "primitives": [{"id": "ring", "type": "torus", "R": 5.0, "r": 1.0},
                              {"id": "ball", "type": "sphere", "r": 2.0}]}, f)
culled = json.loads(run("assemble", f"{work}/ring.json", "--out", f"{work}/ring", "--json").stdout)
assert culled["statistics"]["candidate_pairs"] == 1 and culled["statistics"]["culled_pairs"] == 1, \
    culled["statistics"]
empty = os.path.join(work, "no_modules")
os.makedirs(empty)
for scene, out in ((f"{work}/ring.json", "ring_unculled"), (f"{work}/truth.json", "unculled")):
    p = subprocess.run([binary, "assemble", scene, "--out", f"{work}/{out}", "--json"],
                       capture_output=True, text=True, env={**os.environ, "CSGTILE_MODULE_DIR": empty})
    assert p.returncode == 0, p.stdout + p.stderr
    assert json.loads(p.stdout)["statistics"]["culled_pairs"] == 0, p.stdout
    body_unculled = json.load(open(f"{work}/{out}/assembly.json"))
    assert any(q.startswith("voxel culling skipped") and "libcsgtile_vdb.so is not installed" in q
               for q in body_unculled["problems"]), body_unculled["problems"]
    if out == "unculled":
        assert {o["id"]: (o["primitives"], o["volume"])
                for o in body_unculled["objects"]} == objects
ring_objects = json.load(open(f"{work}/ring_unculled/assembly.json"))["objects"]
assert len(ring_objects) == 2 and all(o["fused"] for o in ring_objects), ring_objects

cells = json.loads(run("assemble", f"{work}/truth.json", "--out", f"{work}/cells", "--json",
                       "--cell-size", "20", "--halo", str(extent + 1)).stdout)
got = {}
for cell in cells["cells"]:
    assert cell["statistics"]["objects_past_halo"] == 0, cell
    i, j = cell["cell"]
    for o in json.load(open(f"{work}/cells/cell_{i}_{j}/assembly.json"))["objects"]:
        assert o["id"] not in got, f"{o['id']} published twice"
        got[o["id"]] = (o["primitives"], o["volume"])
assert got == objects, "cells differ from the whole assembly"
assert abs(cells["total_volume"] - whole["total_volume"]) <= 1e-9 * whole["total_volume"]

# A halo smaller than the objects: reported, never silent.
small = json.loads(run("assemble", f"{work}/truth.json", "--out", f"{work}/small", "--json",
                       "--cell-size", "5", "--halo", "0").stdout)
past = sum(c["statistics"]["objects_past_halo"] for c in small["cells"])
problems = [p for c in small["cells"] for p in c["problems"]]
assert past > 0 and any("reaches past the halo" in p for p in problems), small

# Bad input: a missing file and an unreadable scene are named, exit non-zero.
bad = run("assemble", f"{work}/missing.json", "--out", f"{work}/x", "--json", ok=False)
assert bad.returncode != 0 and "missing.json" in bad.stdout + bad.stderr, bad
with open(f"{work}/broken.json", "w") as f:
    f.write('{"primitives": [{"type": "box", "size": [1, 2]}]}')
bad = run("assemble", f"{work}/broken.json", "--out", f"{work}/x", ok=False)
assert bad.returncode != 0 and "size" in bad.stderr, bad.stderr
print(f"ok: {len(objects)} objects, {len(cells['cells'])} cells, volume {whole['total_volume']:.6f}")
