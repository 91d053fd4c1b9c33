"""The model's top surface and the building points' vertical distances to it (issue #18).

Measured as the buildings field measures a city model against its LIDAR (3DBAG, roofer): on
a grid of `cell` metres (0.5), the top of the model over each cell centre is the highest z
where the vertical line through it meets a solid (the union of the primitives: the fused
model has the same top). Each building point (class 6) is compared with the top over its
cell:
  coverage       share of building points over a cell the model covers;
  within_<t>m    share of building points whose |z - top| <= t (t = 0.1, 0.3, 1; points over
                 no model count as not within);
  rmse_m, median_m  of |z - top| over the covered points;
  false_area     model cells holding no building point, as a share of the model's cells;
  footprints_as_model  (inside_footprints, with footprints) the coverage and false area the
                 published footprints themselves reach as the model, on the same grid: a
                 point whose cell centre lies outside its footprint is uncovered, a cell whose
                 centre lies inside but holds no building point is false (cells within the
                 scanned extent: 2 m blocks holding a point of any class). The grid's own
                 floor: a model whose walls stand exactly on the footprints scores these;
  best_possible  within_<t>m that a perfect model would reach: one top per cell cannot be
                 within t of every point of a cell on a steep roof or a facade;
each over the whole tile and over the points inside the published footprints (when given).

The vertical line meets a box, a cylinder and an extrusion (vertical or lying), each cut by
its clips (the half-spaces of a roof part), exactly; a
cone, sphere, torus or revolution through its analytic inside test, scanned down from the
primitive's top at 5 cm and refined by bisection to 1 mm.
Standard library only; imported by real_tiles.py.
"""
import math

THRESHOLDS = (0.1, 0.3, 1.0)


def _line(prim, x, y):
    """The vertical line through (x, y) in the primitive's local frame: o + t d, t = world z."""
    cols, s, t = prim.frame
    dx, dy, dz = x - t[0], y - t[1], -t[2]
    o = tuple((cols[i][0] * dx + cols[i][1] * dy + cols[i][2] * dz) / s for i in range(3))
    d = tuple(cols[i][2] / s for i in range(3))
    return o, d


def _slab(o, d, lo, hi, interval):
    """Intersects `interval` (t0, t1) with lo <= o + t d <= hi; None when empty."""
    t0, t1 = interval
    if abs(d) < 1e-12:
        return interval if lo <= o <= hi else None
    a, b = (lo - o) / d, (hi - o) / d
    if a > b:
        a, b = b, a
    t0, t1 = max(t0, a), min(t1, b)
    return (t0, t1) if t0 <= t1 else None


def _box_spans(prim, o, d):
    iv = (-math.inf, math.inf)
    for k in range(3):
        iv = _slab(o[k], d[k], 0.0, prim.size[k], iv)
        if iv is None:
            return []
    return [iv]


def _cylinder_spans(prim, o, d):
    r, h = prim.p["r"], prim.p["h"]
    iv = _slab(o[2], d[2], 0.0, h, (-math.inf, math.inf))
    if iv is None:
        return []
    a = d[0] * d[0] + d[1] * d[1]
    b = 2 * (o[0] * d[0] + o[1] * d[1])
    c = o[0] * o[0] + o[1] * o[1] - r * r
    if a < 1e-18:
        return [iv] if c <= 0 else []
    disc = b * b - 4 * a * c
    if disc < 0:
        return []
    q = math.sqrt(disc)
    lo, hi = (-b - q) / (2 * a), (-b + q) / (2 * a)
    t0, t1 = max(iv[0], lo), min(iv[1], hi)
    return [(t0, t1)] if t0 <= t1 else []


def inside_rings(px, py, rings):
    """Even-odd point-in-polygon over several rings (outer + holes)."""
    inside = False
    for ring in rings:
        n = len(ring)
        for i in range(n):
            ax, ay = ring[i]
            bx, by = ring[(i + 1) % n]
            if (ay > py) != (by > py) and px < ax + (py - ay) * (bx - ax) / (by - ay):
                inside = not inside
    return inside


def _extrusion_spans(prim, o, d):
    iv = _slab(o[2], d[2], 0.0, prim.h, (-math.inf, math.inf))
    if iv is None:
        return []
    if abs(d[0]) < 1e-12 and abs(d[1]) < 1e-12:  # the line runs along the extrusion
        return [iv] if inside_rings(o[0], o[1], prim.rings) else []
    # The line crosses the profile's plane: where it is inside the profile (even-odd).
    cuts = []
    for ring in prim.rings:
        n = len(ring)
        for i in range(n):
            ax, ay = ring[i]
            bx, by = ring[(i + 1) % n]
            ex, ey = bx - ax, by - ay
            den = d[0] * ey - d[1] * ex
            if abs(den) < 1e-15:
                continue
            wx, wy = ax - o[0], ay - o[1]
            t = (wx * ey - wy * ex) / den
            u = (wx * d[1] - wy * d[0]) / den
            if 0.0 <= u < 1.0:
                cuts.append(t)
    cuts.sort()
    spans = []
    for k in range(0, len(cuts) - 1, 2):
        t0, t1 = max(iv[0], cuts[k]), min(iv[1], cuts[k + 1])
        if t0 <= t1:
            spans.append((t0, t1))
    return spans


def _clipped(spans, clips, o, d):
    """The spans' parts where n·(o + t d) <= w for every clip (n, w) of the local frame."""
    for nx, ny, nz, w in clips:
        nd = nx * d[0] + ny * d[1] + nz * d[2]
        no = nx * o[0] + ny * o[1] + nz * o[2]
        out = []
        for t0, t1 in spans:
            if abs(nd) < 1e-15:
                if no <= w:
                    out.append((t0, t1))
                continue
            lim = (w - no) / nd
            a, b = (t0, min(t1, lim)) if nd > 0 else (max(t0, lim), t1)
            if a <= b:
                out.append((a, b))
        spans = out
    return spans


def _inside(prim, lx, ly, lz):
    t, p = prim.type, prim.p
    if any(nx * lx + ny * ly + nz * lz > w for nx, ny, nz, w in prim.clips):
        return False
    if t == "sphere":
        return lx * lx + ly * ly + lz * lz <= p["r"] ** 2
    if t == "torus":
        return math.hypot(math.hypot(lx, ly) - p["R"], lz) <= p["r"]
    if t == "cone":
        if not 0.0 <= lz <= p["h"]:
            return False
        return math.hypot(lx, ly) <= p["r1"] + (p["r2"] - p["r1"]) * lz / p["h"]
    # revolution (any angle taken as a full turn)
    return inside_rings(math.hypot(lx, ly), lz, [prim.profile])


def _scanned_top(prim, o, d):
    def inside(z):
        return _inside(prim, o[0] + z * d[0], o[1] + z * d[1], o[2] + z * d[2])
    step = 0.05
    z = prim.hi[2]
    prev = z
    while z >= prim.lo[2] - step:
        if inside(z):
            lo, hi = z, prev  # inside at lo, outside (or the top) at hi
            if hi == z:
                return z
            while hi - lo > 1e-3:
                mid = 0.5 * (lo + hi)
                if inside(mid):
                    lo = mid
                else:
                    hi = mid
            return lo
        prev = z
        z -= step
    return None


def top_of(prim, x, y):
    """Highest world z of `prim` on the vertical line through (x, y); None when it misses."""
    if not (prim.lo[0] <= x <= prim.hi[0] and prim.lo[1] <= y <= prim.hi[1]):
        return None
    o, d = _line(prim, x, y)
    spans = {"box": _box_spans, "cylinder": _cylinder_spans,
             "extrusion": _extrusion_spans}.get(prim.type)
    if spans is None:
        return _scanned_top(prim, o, d)
    found = _clipped(spans(prim, o, d), prim.clips, o, d)
    return max(t1 for _, t1 in found) if found else None


def top_surface(prims, x0, y0, nx, ny, cell):
    """{(i, j): top z} over the cell centres the model covers."""
    bucket = 4.0
    index = {}
    for k, p in enumerate(prims):
        for bi in range(int(math.floor(p.lo[0] / bucket)), int(math.floor(p.hi[0] / bucket)) + 1):
            for bj in range(int(math.floor(p.lo[1] / bucket)), int(math.floor(p.hi[1] / bucket)) + 1):
                index.setdefault((bi, bj), []).append(k)
    tops = {}
    for j in range(ny):
        y = y0 + (j + 0.5) * cell
        for i in range(nx):
            x = x0 + (i + 0.5) * cell
            best = None
            for k in index.get((int(math.floor(x / bucket)), int(math.floor(y / bucket))), ()):
                z = top_of(prims[k], x, y)
                if z is not None and (best is None or z > best):
                    best = z
            if best is not None:
                tops[(i, j)] = best
    return tops


def _figures(dist, count):
    out = {"points": count}
    if count == 0:
        return out
    covered = [v for v in dist if v is not None]
    out["coverage"] = len(covered) / count
    for t in THRESHOLDS:
        out["within_%gm" % t] = sum(1 for v in covered if v <= t) / count
    if covered:
        out["rmse_m"] = math.sqrt(sum(v * v for v in covered) / len(covered))
        s = sorted(covered)
        out["median_m"] = s[len(s) // 2]
    return out


def best_possible(zs_by_cell, count):
    """The most any model can reach under this measure: with one top per cell, the share of
    the points within t of the best single height of their cell (a window of 2t over its
    sorted heights). A sloped roof spreads a cell's points by slope × cell, a facade by the
    wall's height: those points are out of reach whatever the model."""
    out = {}
    if count == 0:
        return out
    for t in THRESHOLDS:
        best = 0
        for zs in zs_by_cell.values():
            zs = sorted(zs)
            j = most = 0
            for k in range(len(zs)):
                while zs[k] - zs[j] > 2 * t:
                    j += 1
                most = max(most, k - j + 1)
            best += most
        out["within_%gm" % t] = best / count
    return out


def measure_top_surface(prims, pts, cell=0.5, inside=None, cells=None):
    """The figures of the module comment. `pts` = (xs, ys, zs, cls) in the fit frame;
    `inside(x, y)` (optional) tells whether a point lies in a published footprint. `cells`
    (optional dict) receives the grid: "x0", "y0", "nx", "ny", "tops" {(i, j): top} and
    "residuals" {(i, j): [z - top of each building point there, None over no model]}."""
    xs, ys, zs, cls = pts
    building = [i for i in range(len(xs)) if cls[i] == 6]
    if not building:
        return {"points": 0}
    x0 = math.floor(min(xs[i] for i in building) / cell) * cell - cell
    y0 = math.floor(min(ys[i] for i in building) / cell) * cell - cell
    for p in prims:
        x0, y0 = min(x0, math.floor(p.lo[0] / cell) * cell), min(y0, math.floor(p.lo[1] / cell) * cell)
    x1 = max([xs[i] for i in building] + [p.hi[0] for p in prims]) + cell
    y1 = max([ys[i] for i in building] + [p.hi[1] for p in prims]) + cell
    nx, ny = int((x1 - x0) / cell) + 1, int((y1 - y0) / cell) + 1
    tops = top_surface(prims, x0, y0, nx, ny, cell)
    occupied = set()
    whole, inner = [], []
    whole_z, inner_z = {}, {}
    for i in building:
        key = (int((xs[i] - x0) / cell), int((ys[i] - y0) / cell))
        occupied.add(key)
        whole_z.setdefault(key, []).append(zs[i])
        is_inner = inside is not None and inside(xs[i], ys[i])
        if is_inner:
            inner_z.setdefault(key, []).append(zs[i])
        top = tops.get(key)
        d = None if top is None else abs(zs[i] - top)
        if cells is not None:
            cells.setdefault("residuals", {}).setdefault(key, []).append(
                None if top is None else zs[i] - top)
        whole.append(d)
        if is_inner:
            inner.append(d)
    out = {"cell_m": cell, "whole_tile": _figures(whole, len(whole))}
    out["whole_tile"]["best_possible"] = best_possible(whole_z, len(whole))
    if inside is not None:
        out["inside_footprints"] = _figures(inner, len(inner))
        out["inside_footprints"]["best_possible"] = best_possible(inner_z, len(inner))
    if cells is not None:
        cells.update({"x0": x0, "y0": y0, "nx": nx, "ny": ny, "tops": tops})
    out["model_cells"] = len(tops)
    out["false_area"] = (sum(1 for k in tops if k not in occupied) / len(tops)) if tops else 0.0
    return out


def footprints_as_model(inside, pts, cell, x0, y0, nx, ny):
    """Coverage of the building points inside the footprints and false area, were the
    footprints (inside(x, y)) the model, on the grid of measure_top_surface (origin x0, y0,
    nx by ny cells of `cell`); false area over the scanned extent only (2 m blocks from the
    grid's origin holding a point)."""
    xs, ys, zs, cls = pts
    footprint = {(i, j) for j in range(ny) for i in range(nx)
                 if inside(x0 + (i + 0.5) * cell, y0 + (j + 0.5) * cell)}
    occupied, scanned = set(), set()
    points = covered = 0
    for i in range(len(xs)):
        scanned.add((int((xs[i] - x0) / 2.0), int((ys[i] - y0) / 2.0)))
        if cls[i] != 6:
            continue
        key = (int((xs[i] - x0) / cell), int((ys[i] - y0) / cell))
        occupied.add(key)
        if inside(xs[i], ys[i]):
            points += 1
            covered += 1 if key in footprint else 0
    cells = [k for k in footprint
             if (int((k[0] + 0.5) * cell / 2.0), int((k[1] + 0.5) * cell / 2.0)) in scanned]
    false = sum(1 for k in cells if k not in occupied)
    return {"coverage": covered / points if points else 0.0,
            "false_area": false / len(cells) if cells else 0.0}
