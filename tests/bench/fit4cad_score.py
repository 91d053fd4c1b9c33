#!/usr/bin/env python3
"""Scores `csgtile fit --segments` on Fit4CAD clouds with the benchmark's own measure.

Usage:
  fit4cad_score.py CSGTILE OUTDIR [--data DIR] [--config C.yaml] [--clouds N,N,...]
                   [--min-dice X] [--min-type X] [--seed N]
  fit4cad_score.py --self-test

For every cloud `train_PCn` of DIR (default ../shared/data/fit4cad): its points
(`Points:=[[x, y, z], ...];`) are written as XYZ text in their own units, fitted with
`csgtile fit XYZ --config C --segments OUTDIR/PCn`, and each ground-truth primitive G
(`train_PCn_primitives.txt`, 1-based point indices; types from `train_PCn_implicit.txt`) is
matched to the predicted segment P (points of one detected surface, with its type) with the
largest |P ∩ G| (ties: the lower surface id; none: every score 0):
  Dice      = 2 |G ∩ P| / (|G| + |P|)
  precision = |G ∩ P| / |P ∩ U|   (U: the points of some ground-truth primitive)
  recall    = |G ∩ P| / |G|
  type      = 1 when P's type is G's.
Scores are averaged over a cloud's primitives, then over the clouds (the benchmark's
`main_ClassificationMeasures.m`, with precision and recall in their right order). Prints one
JSON object: per cloud and the means, seconds, surfaces. Exit 1 when a --min-* threshold is
not met or a cloud's segments break their contract (a label naming no surface, a surface
holding no point or listing another count than its labels), 77 (skip) when the data folder
is absent.
"""

import argparse
import json
import os
import re
import struct
import subprocess
import sys
import tempfile
import time

def read_points(path):
    """The cloud's points: every [x, y, z] triple of the file, in order."""
    text = open(path).read()
    nums = r"[-+0-9.eE]+"
    return [(float(a), float(b), float(c))
            for a, b, c in re.findall(r"\[\s*(%s)\s*,\s*(%s)\s*,\s*(%s)\s*\]" % (nums, nums, nums),
                                      text)]


def read_primitives(path):
    """Ground truth: {k: set of 0-based point indices} of `PrimitiveK:=[i j ...];` lines."""
    out = {}
    for m in re.finditer(r"Primitive(\d+)\s*:=\s*\[([^\]]*)\]", open(path).read()):
        idx = [int(t) - 1 for t in m.group(2).replace(",", " ").split()]
        out[int(m.group(1))] = set(idx)
    return out


def read_types(path):
    """Ground-truth types: {k: 'plane' | 'cylinder' | ...} of `PrimitiveK :=[Type, ...];`."""
    out = {}
    for m in re.finditer(r"Primitive(\d+)\s*:=\s*\[\s*([A-Za-z]+)", open(path).read()):
        out[int(m.group(1))] = m.group(2).lower()
    return out


def score(truth, types, labels, seg_types):
    """The benchmark's measure of one cloud.

    truth: {k: set of point indices}; types: {k: type}; labels: per point, surface id or -1;
    seg_types: {surface id: type}. Returns dict of mean dice, precision, recall, type and the
    per-primitive rows."""
    members = {}
    for i, s in enumerate(labels):
        if s >= 0:
            members.setdefault(s, set()).add(i)
    union = set()
    for g in truth.values():
        union |= g
    rows = []
    for k in sorted(truth):
        g = truth[k]
        best, best_n = None, 0
        for s in sorted(members):
            n = len(g & members[s])
            if n > best_n:
                best, best_n = s, n
        if best is None:
            rows.append({"primitive": k, "type": types.get(k, "?"), "points": len(g),
                         "dice": 0.0, "precision": 0.0, "recall": 0.0, "type_ok": 0,
                         "segment": None})
            continue
        p = members[best]
        in_union = len(p & union)
        rows.append({
            "primitive": k, "type": types.get(k, "?"), "points": len(g), "segment": best,
            "segment_type": seg_types.get(best, "?"),
            "dice": 2.0 * best_n / (len(g) + len(p)),
            "precision": best_n / in_union if in_union else 0.0,
            "recall": best_n / len(g) if g else 0.0,
            "type_ok": 1 if seg_types.get(best) == types.get(k) else 0,
        })
    n = max(len(rows), 1)
    return {
        "dice": sum(r["dice"] for r in rows) / n,
        "precision": sum(r["precision"] for r in rows) / n,
        "recall": sum(r["recall"] for r in rows) / n,
        "type": sum(r["type_ok"] for r in rows) / n,
        "rows": rows,
    }


def read_segments(prefix, count):
    raw = open(prefix + ".i32", "rb").read()
    if len(raw) != 4 * count:
        raise ValueError("%s.i32: %d bytes for %d points" % (prefix, len(raw), count))
    labels = list(struct.unpack("<%di" % count, raw))
    doc = json.load(open(prefix + ".json"))
    problems = segment_problems(labels, doc["surfaces"])
    if problems:
        raise ValueError("%s: %s" % (prefix, "; ".join(problems)))
    seg_types = {s["id"]: s["type"] for s in doc["surfaces"]}
    return labels, seg_types


def segment_problems(labels, surfaces):
    """What breaks the --segments contract: every label is -1 or a listed surface's id, and
    every surface lists as `points` the number of points labelled with its id, at least one."""
    held = {}
    for label in labels:
        held[label] = held.get(label, 0) + 1
    ids = {s["id"] for s in surfaces}
    problems = ["label %d names no surface" % k for k in sorted(held) if k != -1 and k not in ids]
    for s in surfaces:
        n = held.get(s["id"], 0)
        if n == 0:
            problems.append("surface %d holds no point" % s["id"])
        elif n != s["points"]:
            problems.append("surface %d lists %d points, %d are labelled with it"
                            % (s["id"], s["points"], n))
    return problems


def self_test():
    # Two planes and a cylinder over 10 points; point 4 on the edge of both planes.
    truth = {1: {0, 1, 2, 3, 4}, 2: {4, 5, 6}, 3: {7, 8}}
    types = {1: "plane", 2: "plane", 3: "cylinder"}
    # Surface 0 takes 0-4 and stray point 9 (outside every primitive); surface 1 is a cone
    # taking 5, 6, 7; point 8 is unassigned.
    labels = [0, 0, 0, 0, 0, 1, 1, 1, -1, 0]
    seg_types = {0: "plane", 1: "cone"}
    got = score(truth, types, labels, seg_types)
    r1, r2, r3 = got["rows"]
    expect = [
        (r1["dice"], 2 * 5 / (5 + 6)), (r1["precision"], 1.0), (r1["recall"], 1.0),
        (r1["type_ok"], 1),
        # primitive 2: surface 1 holds 2 of its points, surface 0 one (point 4): surface 1.
        (r2["dice"], 2 * 2 / (3 + 3)), (r2["precision"], 2 / 3), (r2["recall"], 2 / 3),
        (r2["type_ok"], 0),
        # primitive 3: surface 1 holds point 7 → dice 2/(2+3), precision 1/3, recall 1/2.
        (r3["dice"], 2 * 1 / (2 + 3)), (r3["precision"], 1 / 3), (r3["recall"], 0.5),
        (r3["type_ok"], 0),
        (got["type"], 1 / 3),
    ]
    for value, want in expect:
        if abs(value - want) > 1e-12:
            print("self-test failed: %r != %r" % (value, want), file=sys.stderr)
            return 1
    # A primitive no segment touches scores 0.
    none = score({1: {0, 1}}, {1: "plane"}, [-1, -1], {})
    if none["dice"] != 0.0 or none["rows"][0]["segment"] is not None:
        print("self-test failed: unmatched primitive", file=sys.stderr)
        return 1
    # The reader of the benchmark's files.
    with tempfile.TemporaryDirectory() as d:
        open(os.path.join(d, "p.txt"), "w").write(
            "Points:=[\n[1.5, -2, 3e-1], \n[0, 0, 0]];\n")
        open(os.path.join(d, "g.txt"), "w").write("Primitive1:=[2 1];\n\nPrimitive2:=[1];\n")
        open(os.path.join(d, "t.txt"), "w").write(
            "Primitive1 :=[Plane, [0 -1 0 -0]];\n\nPrimitive2 :=[Cylinder, [1 2]];\n")
        if read_points(os.path.join(d, "p.txt")) != [(1.5, -2.0, 0.3), (0.0, 0.0, 0.0)]:
            print("self-test failed: points", file=sys.stderr)
            return 1
        if read_primitives(os.path.join(d, "g.txt")) != {1: {0, 1}, 2: {0}}:
            print("self-test failed: primitives", file=sys.stderr)
            return 1
        if read_types(os.path.join(d, "t.txt")) != {1: "plane", 2: "cylinder"}:
            print("self-test failed: types", file=sys.stderr)
            return 1
    if segment_problems([0, 0, -1, 2], [{"id": 0, "points": 2}, {"id": 1, "points": 0}]) != [
            "label 2 names no surface", "surface 1 holds no point"]:
        print("self-test failed: segment problems", file=sys.stderr)
        return 1
    if segment_problems([0, -1, 0], [{"id": 0, "points": 2}]):
        print("self-test failed: a sound segmentation has problems", file=sys.stderr)
        return 1
    print(json.dumps({"self_test": "passed"}))
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("csgtile", nargs="?")
    ap.add_argument("outdir", nargs="?")
    ap.add_argument("--data", default=os.path.join(os.path.dirname(__file__), "..", "..", "..",
                                                   "shared", "data", "fit4cad"))
    ap.add_argument("--config", default=os.path.join(os.path.dirname(__file__), "..", "..",
                                                     "config", "examples", "fit-cad.yaml"))
    ap.add_argument("--clouds", default="", help="comma-separated cloud numbers (default: all)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--min-dice", type=float, default=None)
    ap.add_argument("--min-type", type=float, default=None)
    ap.add_argument("--rows", action="store_true", help="print every primitive's row")
    ap.add_argument("--expect", action="append", default=[], metavar="N:K:TYPE:DICE",
                    help="fail unless primitive K of cloud N is found as a segment of TYPE "
                         "with Dice >= DICE (repeatable; a named failure case)")
    ap.add_argument("--self-test", action="store_true")
    a = ap.parse_args()
    if a.self_test:
        return self_test()
    if not a.csgtile or not a.outdir:
        ap.error("CSGTILE and OUTDIR are required")
    if not os.path.isdir(a.data):
        print("fit4cad_score: no data folder %s: skipped" % a.data, file=sys.stderr)
        return 77
    names = sorted(int(m.group(1)) for f in os.listdir(a.data)
                   for m in [re.fullmatch(r"train_PC(\d+)\.txt", f)] if m)
    if a.clouds:
        wanted = {int(t) for t in a.clouds.split(",")}
        names = [n for n in names if n in wanted]
    if not names:
        print("fit4cad_score: no cloud train_PCn.txt in %s" % a.data, file=sys.stderr)
        return 77
    expects = []
    for e in a.expect:
        parts = e.split(":")
        if len(parts) != 4:
            ap.error("--expect %s: want CLOUD:PRIMITIVE:TYPE:DICE" % e)
        expects.append((int(parts[0]), int(parts[1]), parts[2], float(parts[3])))
    os.makedirs(a.outdir, exist_ok=True)
    clouds = []
    unmet = []
    for n in names:
        stem = os.path.join(a.data, "train_PC%d" % n)
        pts = read_points(stem + ".txt")
        truth = read_primitives(stem + "_primitives.txt")
        types = read_types(stem + "_implicit.txt")
        xyz = os.path.join(a.outdir, "PC%d.xyz" % n)
        with open(xyz, "w") as f:
            for p in pts:
                f.write("%.9g %.9g %.9g\n" % p)
        prefix = os.path.join(a.outdir, "PC%d" % n)
        cmd = [a.csgtile, "fit", xyz, "--config", a.config, "--seed", str(a.seed), "--out",
               prefix + ".scene.json", "--segments", prefix, "--json"]
        t = time.time()
        run = subprocess.run(cmd, capture_output=True, text=True)
        seconds = time.time() - t
        if run.returncode != 0:
            print("fit4cad_score: %s failed (%d): %s%s" % (" ".join(cmd), run.returncode,
                                                           run.stdout, run.stderr),
                  file=sys.stderr)
            return 1
        try:
            labels, seg_types = read_segments(prefix, len(pts))
        except ValueError as e:
            print("fit4cad_score: %s" % e, file=sys.stderr)
            return 1
        s = score(truth, types, labels, seg_types)
        row = {"cloud": "train_PC%d" % n, "points": len(pts), "primitives": len(truth),
               "surfaces": len(seg_types), "seconds": round(seconds, 3),
               "dice": s["dice"], "precision": s["precision"], "recall": s["recall"],
               "type": s["type"]}
        if a.rows:
            row["rows"] = s["rows"]
        for cloud, k, want, dice in expects:
            if cloud != n:
                continue
            got = next((r for r in s["rows"] if r["primitive"] == k), None)
            if got is None or got.get("segment_type") != want or got["dice"] < dice:
                unmet.append("train_PC%d primitive %d: want %s with Dice >= %.2f, got %s" % (
                    n, k, want, dice, "nothing" if got is None else "%s with Dice %.3f" % (
                        got["segment_type"], got["dice"])))
        clouds.append(row)
    mean = {k: sum(c[k] for c in clouds) / len(clouds)
            for k in ("dice", "precision", "recall", "type")}
    print(json.dumps({"config": os.path.relpath(a.config), "seed": a.seed, "clouds": clouds,
                      "mean": mean}, indent=1))
    ok = not unmet
    for u in unmet:
        print("fit4cad_score: %s" % u, file=sys.stderr)
    if a.min_dice is not None and mean["dice"] < a.min_dice:
        print("fit4cad_score: mean Dice %.4f < %.4f" % (mean["dice"], a.min_dice),
              file=sys.stderr)
        ok = False
    if a.min_type is not None and mean["type"] < a.min_type:
        print("fit4cad_score: type accuracy %.4f < %.4f" % (mean["type"], a.min_type),
              file=sys.stderr)
        ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
