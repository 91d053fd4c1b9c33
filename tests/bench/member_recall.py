#!/usr/bin/env python3
"""Members of a frame found by volume overlap: recall per member kind and precision.

Usage: member_recall.py --truth T.json --fit F.json [--las SCAN.las --min-points 50]
                        [--iou 0.7 --samples 400 --seed 1]

The measure of issue #21: a truth primitive is found when a fitted primitive of the same
type overlaps it with volume IoU >= --iou (0.7); matching is one-to-one, greedy by IoU. The
member kind is the truth id's first word (column, beam, brace, ...). With --las, only truth
primitives hit by at least --min-points points of the scan (its "truth_index" dimension)
count. Precision: fitted primitives matched / all fitted primitives. Volumes are estimated by
--samples seeded uniform samples in each truth primitive (box, cylinder, cone) tested against
each fitted one whose bounding box meets it. Prints one JSON object.

  B/csgtile synth gate --mode terrestrial --points 1000000 --out gate.las --truth gate.json
  B/csgtile fit gate.las --config tests/bench/fit_terrestrial.yaml --out fit.json
  python3 tests/bench/member_recall.py --truth gate.json --fit fit.json --las gate.las
"""
import argparse
import collections
import json
import math
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fit_recall as fr  # noqa: E402


def frame(p):
    """Rotation columns normalised, and translation."""
    rot, t = fr.mat(p)
    cols = [fr.col(rot, c) for c in range(3)]
    return cols, t


def to_local(p, x):
    cols, t = p["_frame"]
    d = [x[i] - t[i] for i in range(3)]
    return [sum(cols[c][r] * d[r] for r in range(3)) for c in range(3)]


def to_world(p, q):
    cols, t = p["_frame"]
    return [t[r] + sum(cols[c][r] * q[c] for c in range(3)) for r in range(3)]


def height(p):
    return p.get("h", p.get("height", 0.0))


def local_bounds(p):
    kind = p["type"]
    if kind == "box":
        return [0.0, 0.0, 0.0], list(p["size"])
    if kind == "cylinder":
        r = p["r"]
        return [-r, -r, 0.0], [r, r, height(p)]
    if kind == "cone":
        r = max(p.get("r1", 0.0), p.get("r2", 0.0))
        return [-r, -r, 0.0], [r, r, height(p)]
    if kind == "extrusion" and p.get("profile"):
        xs = [v[0] for v in p["profile"]]
        ys = [v[1] for v in p["profile"]]
        return [min(xs), min(ys), 0.0], [max(xs), max(ys), height(p)]
    return None


def world_box(p):
    b = local_bounds(p)
    if b is None:
        return None
    lo, hi = b
    corners = [to_world(p, [(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]])
               for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    return ([min(c[a] for c in corners) for a in range(3)],
            [max(c[a] for c in corners) for a in range(3)])


def inside(p, x):
    q = to_local(p, x)
    kind = p["type"]
    if kind == "box":
        return all(0.0 <= q[a] <= p["size"][a] for a in range(3))
    h = height(p)
    if not 0.0 <= q[2] <= h:
        return False
    if kind == "cylinder":
        return q[0] ** 2 + q[1] ** 2 <= p["r"] ** 2
    if kind == "cone":
        r = p["r1"] + (p["r2"] - p["r1"]) * (q[2] / h if h > 0 else 0.0)
        return q[0] ** 2 + q[1] ** 2 <= r * r
    if kind == "extrusion":
        return fr.inside(q[0], q[1], p["profile"])
    return False


def volume(p):
    kind = p["type"]
    if kind == "box":
        s = p["size"]
        return s[0] * s[1] * s[2]
    if kind == "cylinder":
        return math.pi * p["r"] ** 2 * height(p)
    if kind == "cone":
        r1, r2 = p["r1"], p["r2"]
        return math.pi * height(p) * (r1 * r1 + r1 * r2 + r2 * r2) / 3.0
    return None


def samples(p, n, rng):
    lo, hi = local_bounds(p)
    out = []
    while len(out) < n:
        q = [lo[a] + rng.random() * (hi[a] - lo[a]) for a in range(3)]
        x = to_world(p, q)
        if inside(p, x):
            out.append(x)
    return out


def member_kind(truth):
    return truth.get("id", truth["type"]).split("-")[0]


def overlaps(a, b):
    return all(a[0][k] <= b[1][k] and b[0][k] <= a[1][k] for k in range(3))


def main():
    ap = argparse.ArgumentParser()
    fr.scan_arguments(ap)
    ap.add_argument("--iou", type=float, default=0.7)
    ap.add_argument("--samples", type=int, default=400)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    truth = json.load(open(args.truth))["primitives"]
    fit = json.load(open(args.fit))["primitives"]
    for p in truth + fit:
        p["_frame"] = frame(p)
        p["_box"] = world_box(p)
    visible = (fr.visible_counts(args.las, len(truth)) if args.las
               else [args.min_points] * len(truth))
    rng = random.Random(args.seed)
    pairs = []  # (iou, truth index, fit index)
    counted = [i for i, t in enumerate(truth)
               if visible[i] >= args.min_points and volume(t) is not None]
    for i in counted:
        t = truth[i]
        vt = volume(t)
        pts = None
        for j, f in enumerate(fit):
            if f["type"] != t["type"] or f["_box"] is None or not overlaps(t["_box"], f["_box"]):
                continue
            vf = volume(f)
            if vf is None:
                continue
            if pts is None:
                pts = samples(t, args.samples, rng)
            common = vt * sum(1 for x in pts if inside(f, x)) / len(pts)
            if common > 0.0:
                pairs.append((common / (vt + vf - common), i, j))
    pairs.sort(key=lambda e: (-e[0], e[1], e[2]))
    taken_t, taken_f, best = set(), set(), {}
    for iou, i, j in pairs:
        best[i] = max(best.get(i, 0.0), iou)
        if iou < args.iou or i in taken_t or j in taken_f:
            continue
        taken_t.add(i)
        taken_f.add(j)
    kinds = collections.OrderedDict()
    for i in counted:
        k = kinds.setdefault(member_kind(truth[i]), {"visible": 0, "found": 0, "iou_sum": 0.0})
        k["visible"] += 1
        k["found"] += 1 if i in taken_t else 0
        k["iou_sum"] += best.get(i, 0.0)
    out = {"iou": args.iou, "fitted": len(fit), "matched": len(taken_f),
           "precision": len(taken_f) / len(fit) if fit else 0.0,
           "recall": len(taken_t) / len(counted) if counted else 0.0, "kinds": {}}
    for name, k in kinds.items():
        out["kinds"][name] = {"visible": k["visible"], "found": k["found"],
                              "recall": k["found"] / k["visible"],
                              "mean_best_iou": k["iou_sum"] / k["visible"]}
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
