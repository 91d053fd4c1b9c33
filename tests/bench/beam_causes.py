#!/usr/bin/env python3
"""Why each truth box (beam) of a synthetic scene is or is not matched by a fitted box.

Usage: beam_causes.py --truth T.json --fit F.json --fit-json OUT.json --dump DUMP.txt
                      --las SCAN.las [--position 0.02 --angle 5 --min-points 50] [--rows]

DUMP.txt is written by `csgtile fit --dump-shapes DUMP.txt` (every region's points with
their normals and RANSAC shape, and the detected shapes); OUT.json is `csgtile fit --json`'s
output (for the rejections). For the gate of issue #6 (build dir B):
  B/csgtile synth gate --mode terrestrial --points 1000000 --out gate.las --truth gate.json
  B/csgtile fit gate.las --out fit.json --dump-shapes dump.txt --json > out.json
  python3 tests/bench/beam_causes.py --truth gate.json --fit fit.json --fit-json out.json \
      --dump dump.txt --las gate.las

For every visible truth box: the fitter's points on it (within 3 cm of its surface and
nearer to it than to any other truth primitive), per face (bottom, top, the two sides, the two
ends) and whether a RANSAC plane parallel to that face holds most of them; the fitted boxes
overlapping it, the best of them and its errors in the truth's frame (centre offset along the
length, across, in depth; size differences); and one cause:
  matched                 fit_recall's one-to-one match within --position
  no plane                no face has a RANSAC plane with >= 50% of its points
  plane but no box        a plane exists, no fitted box overlaps the beam (the plane's
                          rejection reason is listed)
  merged                  the best box also covers >= 50% of another truth box
  taken                   the best box matched another truth box
  orientation             the best box's edges are more than --angle off the truth's
  depth / across / length the largest centre offset of the best box is in that direction
Prints a table of causes and, with --rows, one line per beam.
"""
import argparse
import collections
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fit_recall as fr  # noqa: E402


def frame(p):
    """World → local of a truth or fitted box: rotation columns, origin, size (unscaled)."""
    rot, t = fr.mat(p)
    s = fr.scale(p)
    cols = [[rot[r][c] / s for r in range(3)] for c in range(3)]
    size = [x * s for x in p["size"]]
    return cols, t, size


def to_local(f, q):
    cols, t, _ = f
    d = fr.sub(q, t)
    return [fr.dot(d, c) for c in cols]


def surface_distance(f, q):
    """Distance of q from a box's surface and the face it is nearest (0..5: -x +x -y +y -z +z)."""
    loc = to_local(f, q)
    size = f[2]
    out = [max(-loc[k], 0.0, loc[k] - size[k]) for k in range(3)]
    if any(o > 0.0 for o in out):
        dist = math.sqrt(sum(o * o for o in out))
        k = max(range(3), key=lambda j: out[j])
        return dist, 2 * k + (1 if loc[k] > size[k] else 0)
    best = None
    for k in range(3):
        for side, d in ((0, loc[k]), (1, size[k] - loc[k])):
            if best is None or d < best[0]:
                best = (d, 2 * k + side)
    return best


def cylinder_distance(p, q):
    rot, t = fr.mat(p)
    s = fr.scale(p)
    a = fr.col(rot, 2)
    d = fr.sub(q, t)
    h = fr.dot(d, a)
    radial = fr.norm([d[i] - h * a[i] for i in range(3)])
    return abs(radial - p["r"] * s) if -0.03 <= h <= p["h"] * s + 0.03 else 1e9


def face_names(f):
    """Names of the six faces of a truth box: its longest edge is the length, z the depth."""
    size = f[2]
    names = []
    length = max(range(3), key=lambda k: size[k])
    for k in range(3):
        up = f[0][k][2]
        for side in (0, 1):
            if abs(up) > 0.9:
                names.append("bottom" if (side == 0) == (up > 0) else "top")
            elif k == length:
                names.append("end")
            else:
                names.append("side")
    return names


def overlap(a, b, n=6):
    """Share of box a's volume inside box b (n³ samples)."""
    cols, t, size = a
    inside = 0
    for i in range(n):
        for j in range(n):
            for k in range(n):
                loc = [size[0] * (i + 0.5) / n, size[1] * (j + 0.5) / n, size[2] * (k + 0.5) / n]
                w = [t[r] + sum(cols[c][r] * loc[c] for c in range(3)) for r in range(3)]
                lb = to_local(b, w)
                inside += all(-1e-9 <= lb[m] <= b[2][m] + 1e-9 for m in range(3))
    return inside / n ** 3


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--truth", required=True)
    ap.add_argument("--fit", required=True)
    ap.add_argument("--fit-json", required=True)
    ap.add_argument("--dump", required=True)
    ap.add_argument("--las", required=True)
    ap.add_argument("--position", type=float, default=0.02)
    ap.add_argument("--angle", type=float, default=5.0)
    ap.add_argument("--radius", type=float, default=0.02)
    ap.add_argument("--iou", type=float, default=0.8)
    ap.add_argument("--extent", type=float, default=0.04)
    ap.add_argument("--min-points", type=int, default=50)
    ap.add_argument("--rows", action="store_true")
    ap.add_argument("--min-shape", type=int, default=40, help="the RANSAC's min_points")
    ap.add_argument("--normal-deviation", type=float, default=25.0,
                    help="the RANSAC's normal_deviation_deg")
    tol = ap.parse_args()
    truth = json.load(open(tol.truth))["primitives"]
    fitted = json.load(open(tol.fit))["primitives"]
    fit_out = json.load(open(tol.fit_json))
    rejected = fit_out.get("rejected", [])
    region_eps = {r: st["cluster_epsilon"] for r, st in enumerate(fit_out.get("region_stats", []))}
    cos_dev = math.cos(math.radians(tol.normal_deviation))
    hits = fr.visible_counts(tol.las, len(truth))

    # fit_recall's matching.
    td = [fr.describe(p) for p in truth]
    fd = [fr.describe(p) for p in fitted]
    pairs = []
    for i, t in enumerate(td):
        for j, f in enumerate(fd):
            e = fr.match_error(t, f, tol)
            if e is not None:
                pairs.append((e, i, j))
    pairs.sort()
    t_used, f_used = {}, {}
    for e, i, j in pairs:
        if i in t_used or j in f_used:
            continue
        t_used[i] = j
        f_used[j] = i

    boxes = [i for i, p in enumerate(truth) if p["type"] == "box" and hits[i] >= tol.min_points]
    frames = {i: frame(truth[i]) for i, p in enumerate(truth) if p["type"] == "box"}
    cylinders = [p for p in truth if p["type"] == "cylinder"]

    # The dump: points and shapes per region.
    points = []
    shapes = {}
    with open(tol.dump) as fh:
        for line in fh:
            w = line.split()
            if w[0] == "P":
                points.append((int(w[1]), [float(x) for x in w[2:5]],
                               [float(x) for x in w[5:8]], int(w[8])))
            elif w[0] == "S":
                shapes[(int(w[1]), int(w[2]))] = {
                    "type": int(w[3]), "axis": [float(x) for x in w[7:10]], "inliers": int(w[10])}
    reasons = collections.defaultdict(list)
    for r in rejected:
        words = r["what"].split()
        # "region R plane S" or "region R box from plane S"
        if len(words) >= 4 and words[0] == "region" and words[-2] == "plane":
            reasons[(int(words[1]), int(words[-1]))].append(r["reason"])

    # Points to truth boxes: nearest surface within 3 cm, columns compete.
    cell = 1.0
    grid = collections.defaultdict(list)
    for i, f in frames.items():
        cols, t, size = f
        corners = [[t[r] + sum(cols[c][r] * (size[c] if (m >> c) & 1 else 0.0) for c in range(3))
                    for r in range(3)] for m in range(8)]
        lo = [math.floor((min(c[r] for c in corners) - 0.05) / cell) for r in range(3)]
        hi = [math.floor((max(c[r] for c in corners) + 0.05) / cell) for r in range(3)]
        for x in range(lo[0], hi[0] + 1):
            for y in range(lo[1], hi[1] + 1):
                for z in range(lo[2], hi[2] + 1):
                    grid[(x, y, z)].append(i)
    cgrid = collections.defaultdict(list)
    for p in cylinders:
        d = fr.describe(p)
        c = d["centre"]
        for x in range(math.floor((c[0] - 0.5) / cell), math.floor((c[0] + 0.5) / cell) + 1):
            for y in range(math.floor((c[1] - 0.5) / cell), math.floor((c[1] + 0.5) / cell) + 1):
                cgrid[(x, y)].append(p)
    per_box = collections.defaultdict(lambda: collections.defaultdict(list))  # box → face → pts
    for k, (region, q, n, s) in enumerate(points):
        key = tuple(math.floor(q[r] / cell) for r in range(3))
        best = None
        for i in grid.get(key, []):
            d, face = surface_distance(frames[i], q)
            if d <= 0.03 and (best is None or d < best[0]):
                best = (d, i, face)
        if best is None:
            continue
        if any(cylinder_distance(c, q) < best[0] for c in cgrid.get(key[:2], [])):
            continue
        per_box[best[1]][best[2]].append(k)

    fitted_boxes = [j for j, p in enumerate(fitted) if p["type"] == "box"]
    fframes = {j: frame(fitted[j]) for j in fitted_boxes}
    causes = collections.Counter()
    rows = []
    offsets = collections.defaultdict(list)
    for i in boxes:
        f = frames[i]
        names = face_names(f)
        faces = collections.Counter()
        planes = {}
        for face, ks in per_box[i].items():
            faces[names[face]] += len(ks)
            normal = f[0][face // 2]
            by_shape = collections.Counter(
                (points[k][0], points[k][3]) for k in ks if points[k][3] >= 0)
            parallel = 0
            shape_keys = []
            for key, c in by_shape.items():
                sh = shapes.get(key)
                if sh and sh["type"] == 0 and abs(fr.dot(sh["axis"], normal)) > math.cos(
                        math.radians(10)):
                    parallel += c
                    shape_keys.append(key)
            if len(ks) >= 8:
                planes[names[face]] = planes.get(names[face], False) or parallel >= 0.5 * len(ks)
            if parallel >= 0.5 * len(ks):
                for key in shape_keys:
                    planes.setdefault("_keys", set()).add(key)
        cols, t, size = f
        length_axis = max(range(3), key=lambda k: size[k])
        depth_axis = max((k for k in range(3) if k != length_axis), key=lambda k: abs(cols[k][2]))
        across_axis = 3 - length_axis - depth_axis
        # Best overlapping fitted box: most of the truth inside it, then most of it inside truth.
        cands = []
        for j in fitted_boxes:
            a = overlap(f, fframes[j], 5)
            if a > 0.0:
                cands.append((a, overlap(fframes[j], f, 5), j))
        cands.sort(reverse=True)
        row = {"id": truth[i].get("id", str(i)), "hits": hits[i], "points": dict(faces),
               "planes": {k: v for k, v in planes.items() if k != "_keys"}}
        # Points whose estimated normal is within the RANSAC's deviation of their face's normal
        # (only those can join a plane), the most on one face, and the largest piece of them
        # connected at the region's connectivity size (as the RANSAC's component check sees it).
        good_face, good_piece, good_taken = 0, 0, 0
        for face, ks in per_box[i].items():
            normal = f[0][face // 2]
            good = [k for k in ks if abs(fr.dot(points[k][2], normal)) >= cos_dev]
            if len(good) <= good_face:
                continue
            good_face = len(good)
            region = collections.Counter(points[k][0] for k in good).most_common(1)[0][0]
            eps = region_eps.get(region, 0.1)
            cells = collections.defaultdict(list)
            for k in good:
                cells[tuple(math.floor(points[k][1][r] / eps) for r in range(3))].append(k)
            seen, largest = set(), 0
            for start in cells:
                if start in seen:
                    continue
                seen.add(start)
                queue, grown = [start], 0
                while queue:
                    cur = queue.pop()
                    grown += len(cells[cur])
                    for dx in (-1, 0, 1):
                        for dy in (-1, 0, 1):
                            for dz in (-1, 0, 1):
                                nb = (cur[0] + dx, cur[1] + dy, cur[2] + dz)
                                if nb in cells and nb not in seen:
                                    seen.add(nb)
                                    queue.append(nb)
                largest = max(largest, grown)
            good_piece = largest
            good_taken = sum(1 for k in good if points[k][3] >= 0 and shapes.get(
                (points[k][0], points[k][3]), {}).get("type", 0) != 0)
        row["face_true_normals"] = {"most_on_a_face": good_face, "largest_connected": good_piece,
                                    "in_curved_shapes": good_taken}
        if i in t_used:
            cause = "matched"
        elif not cands:
            if not any(v for k, v in planes.items() if k != "_keys"):
                if good_face < tol.min_shape:
                    cause = "no plane: < min_points face-true normals on any face"
                elif good_piece < tol.min_shape:
                    cause = "no plane: face-true normals in pieces < min_points at the connectivity"
                elif good_taken >= 0.5 * good_face:
                    cause = "no plane: points taken by curved shapes"
                else:
                    cause = "no plane: other"
            else:
                cause = "plane but no box"
                rs = collections.Counter()
                for key in planes.get("_keys", ()):
                    for r in reasons.get(key, []):
                        rs[r] += 1
                row["reasons"] = dict(rs)
        else:
            a, b, j = cands[0]
            fb = fframes[j]
            row["box"] = {"covers": round(a, 2), "inside": round(b, 2), "size": [
                round(x, 3) for x in sorted(fb[2])]}
            others = [k for k in frames if k != i and overlap(frames[k], fb, 4) >= 0.5]
            tc = fr.describe(truth[i])["centre"]
            fc = fr.describe(fitted[j])["centre"]
            d = fr.sub(fc, tc)
            off = {"length": fr.dot(d, cols[length_axis]), "across": fr.dot(d, cols[across_axis]),
                   "depth": fr.dot(d, cols[depth_axis])}
            # Fitted extents along the truth's axes.
            ext = {}
            for name, ax in (("length", length_axis), ("across", across_axis),
                             ("depth", depth_axis)):
                ext[name] = sum(abs(fr.dot(fb[0][c], cols[ax])) * fb[2][c] for c in range(3)) - \
                    size[ax]
            row["offset"] = {k: round(v, 3) for k, v in off.items()}
            row["size_error"] = {k: round(v, 3) for k, v in ext.items()}
            ang = max(min(fr.angle_deg(a_, b_) for b_ in fr.describe(fitted[j])["axes"])
                      for a_ in fr.describe(truth[i])["axes"])
            if others:
                cause = "merged"
                row["merged_with"] = len(others)
            elif ang > tol.angle:
                cause = "orientation"
            elif j in f_used:
                cause = "taken"
            else:
                worst = max(off, key=lambda k: abs(off[k]))
                cause = worst
                offsets[worst].append(abs(off[worst]))
                if worst == "length":
                    # Where each end of the fitted box lies against the truth's (negative: short).
                    ends = [-(off["length"] - ext["length"] / 2), off["length"] + ext["length"] / 2]
                    row["end_errors"] = [round(e, 3) for e in ends]
                    if all(-0.25 <= e <= 0.0 for e in ends):
                        cause = "length: both ends stop at the crossing (<= 0.25 m short)"
                    elif min(ends) < -0.25:
                        cause = "length: an end > 0.25 m short (a face's run breaks off)"
                    else:
                        cause = "length: an end beyond the node"
        causes[cause] += 1
        row["cause"] = cause
        rows.append(row)
    face_tot = collections.Counter()
    plane_tot = collections.Counter()
    for r in rows:
        for k, v in r["points"].items():
            face_tot[k] += v
        for k, v in r["planes"].items():
            plane_tot[k + (" plane" if v else " no plane")] += 1
    out = {"visible_boxes": len(boxes), "causes": dict(causes.most_common()),
           "faces_points": dict(face_tot), "faces_with_plane": dict(plane_tot),
           "offset_median": {k: round(sorted(v)[len(v) // 2], 3) for k, v in offsets.items()}}
    if tol.rows:
        for r in rows:
            print(json.dumps(r))
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
