#!/usr/bin/env python3
"""How often the exact fuse holds on primitives as a fit leaves them (issue #20's test of the
fitted gate): the true primitives of `csgtile synth gate` (81 columns, 148 beams and braces)
each moved at random by up to +-AMP (translation per axis, a rotation of up to AMP/2 rad about
one random axis, each size and radius changed by up to +-AMP), then fused by `csgtile bool`.
A trial holds when the result is valid and one solid. Seeded (trial k uses seed k), so a
failing trial can be replayed and cut down to its failing pair.

With --snap-distance D (and --snap-angle DEG), `csgtile bool` first snaps the primitives'
near-coincidences (kernel/snap.h, the fuzzy mode for fitted primitives); the volume is then
compared with the true primitives' union (relative error, the largest over the trials that
held).
Usage: perturbed_gate.py CSGTILE WORK_DIR [--trials 30] [--amplitude 0.002]
                         [--snap-distance D --snap-angle DEG]
Prints one JSON object: trials, held, failed (trial, error), seconds per trial (median).
"""
import argparse
import json
import math
import os
import random
import statistics
import subprocess
import sys

parser = argparse.ArgumentParser()
parser.add_argument("binary")
parser.add_argument("work")
parser.add_argument("--trials", type=int, default=30)
parser.add_argument("--amplitude", type=float, default=0.002)
parser.add_argument("--snap-distance", type=float, default=0.0)
parser.add_argument("--snap-angle", type=float, default=0.0)
args = parser.parse_args()
snap = []
if args.snap_distance > 0 or args.snap_angle > 0:
    snap = ["--snap-distance", str(args.snap_distance), "--snap-angle", str(args.snap_angle)]
os.makedirs(args.work, exist_ok=True)
truth_path = os.path.join(args.work, "gate_truth.json")
subprocess.run([args.binary, "synth", "gate", "--mode", "terrestrial", "--points", "20000",
                "--out", os.path.join(args.work, "gate.las"), "--truth", truth_path],
               check=True, capture_output=True)
truth = json.load(open(truth_path))
truth["op"] = "fuse"
json.dump(truth, open(truth_path, "w"))
true_volume = json.loads(subprocess.run([args.binary, "bool", truth_path, "--json"],
                                        capture_output=True, text=True).stdout)["volume"]


def perturbed(seed, amp):
    rng = random.Random(seed)
    scene = json.loads(json.dumps(truth))
    for p in scene["primitives"]:
        rows = p["placement"]
        for row in rows:
            row[3] += rng.uniform(-amp, amp)
        angle = rng.uniform(-amp, amp) / 2.0
        c, s = math.cos(angle), math.sin(angle)
        i, j = [(1, 2), (0, 2), (0, 1)][rng.randrange(3)]
        for row in rows:  # the frame's columns i and j turned in their plane
            x, y = row[i], row[j]
            row[i], row[j] = c * x - s * y, s * x + c * y
        for key in ("r", "h"):
            if key in p:
                p[key] += rng.uniform(-amp, amp)
        if "size" in p:
            p["size"] = [v + rng.uniform(-amp, amp) for v in p["size"]]
    return scene


failed, seconds, volume_error = [], [], 0.0
for trial in range(args.trials):
    path = os.path.join(args.work, f"trial_{trial}.json")
    json.dump(perturbed(trial, args.amplitude), open(path, "w"))
    out = subprocess.run([args.binary, "bool", path, "--json", *snap], capture_output=True,
                         text=True)
    try:
        result = json.loads(out.stdout)
    except json.JSONDecodeError:
        result = {"valid": False, "error": out.stderr.strip()[-300:]}
    if result.get("valid") and result["topology"]["solids"] == 1:
        seconds.append(result["seconds"])
        volume_error = max(volume_error, abs(result["volume"] - true_volume) / true_volume)
        os.remove(path)
    else:
        failed.append({"trial": trial, "error": result.get("error")})
print(json.dumps({"trials": args.trials, "amplitude": args.amplitude,
                  "snap_distance": args.snap_distance, "snap_angle": args.snap_angle,
                  "held": args.trials - len(failed), "failed": failed,
                  "true_volume": true_volume, "max_volume_error": volume_error,
                  "median_seconds": statistics.median(seconds) if seconds else None}))
sys.exit(0)
