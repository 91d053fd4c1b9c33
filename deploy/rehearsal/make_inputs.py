#!/usr/bin/env python3
"""Writes the rehearsal's city: shifted copies of the sample scenes (config/examples/scenes,
light jobs) and of the synthetic timber gate (`csgtile synth gate` ground truth, 229
primitives fused: heavy jobs of a few seconds, long enough to cut a worker's link mid-job).
Every copy sits in its own place, so objects of different jobs do not meet.

Usage: make_inputs.py CSGTILE REPO_DIR OUT_DIR LIGHT_COPIES HEAVY_COPIES
Prints the input paths, one per line, in enqueue order (heavy and light interleaved)."""
import copy
import glob
import json
import os
import subprocess
import sys

binary, repo, out, light_copies, heavy_copies = sys.argv[1:6]
light_copies, heavy_copies = int(light_copies), int(heavy_copies)
os.makedirs(out, exist_ok=True)


def shifted(scene, name, dx, dy):
    s = copy.deepcopy(scene)
    s["name"] = name
    for p in s["primitives"]:
        m = p.get("placement", [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]])
        m[0][3] += dx
        m[1][3] += dy
        p["placement"] = m
    return s


def write(scene):
    path = os.path.join(out, scene["name"] + ".json")
    with open(path, "w") as f:
        json.dump(scene, f)
    return path


subprocess.run([binary, "synth", "gate", "--points", "1000", "--out", os.path.join(out, "gate.las"),
                "--truth", os.path.join(out, "gate-truth.json")], check=True, capture_output=True)
gate = json.load(open(os.path.join(out, "gate-truth.json")))
# Model coordinates, like the sample scenes (which have no CRS).
gate = {"name": "gate", "op": "fuse", "primitives": gate["primitives"]}

heavy = [write(shifted(gate, f"gate-{k:02d}", 0.0, 500.0 * (k + 1))) for k in range(heavy_copies)]
light = []
for k in range(light_copies):
    for n, path in enumerate(sorted(glob.glob(os.path.join(repo, "config/examples/scenes/*.json")))):
        base = json.load(open(path))
        stem = os.path.splitext(os.path.basename(path))[0]
        light.append(write(shifted(base, f"{stem}-{k:02d}", 200.0 * (k + 1), -200.0 * (n + 1))))
# Interleaved, so heavy jobs are claimed while the run is in full swing.
order = []
while heavy or light:
    if heavy:
        order.append(heavy.pop(0))
    order.extend(light[:2])
    del light[:2]
print("\n".join(order))
