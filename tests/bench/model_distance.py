"""Each building point's 3D distance to a published city model (issue #18's quality measure).

The field measures a building model against its LIDAR by the 3D distance of each point to
the model's surface: 3DBAG publishes `b3_rmse_lod22`, "the RMSE of the 3D distances between
the point cloud and the LoD2.2 model". Here the model is what a city run published: every
surface of the highest LoD of each CityJSON feature (2.2 where the object reached it, else
its LoD1.3 / 1.2 block, else its curved primitives' surfaces) read from the cells'
CityJSONSeq files. A point's distance is exact to the nearest planar polygon with its holes:
the distance to its plane where the projection falls inside, else to its nearest boundary
edge. Surfaces are binned on a 2 m grid in x, y and searched outwards ring by ring until no
farther cell can hold a closer surface (up to SEARCH_LIMIT metres; a point farther from every
surface counts at that distance and as not covered).

Reported (`measure`): share of points within 0.1 / 0.3 / 1 m, RMSE, median, the share with a
surface within SEARCH_LIMIT, and per published object (each point given to the object of its
nearest surface) the median of the objects' RMSEs. Standard library only; imported by
city_quality.py.
"""
import glob
import json
import math
import os

THRESHOLDS = (0.1, 0.3, 1.0)
CELL = 2.0          # metres, grid of surface bins
SEARCH_LIMIT = 20.0  # metres


class Surface:
    """A planar polygon (outer ring + holes) ready for point distances."""
    __slots__ = ("obj", "n", "d", "u", "v", "rings2", "edges", "lo", "hi")

    def __init__(self, obj, rings):
        self.obj = obj
        outer = rings[0]
        nx = ny = nz = 0.0
        m = len(outer)
        for i in range(m):
            ax, ay, az = outer[i]
            bx, by, bz = outer[(i + 1) % m]
            nx += (ay - by) * (az + bz)
            ny += (az - bz) * (ax + bx)
            nz += (ax - bx) * (ay + by)
        length = math.sqrt(nx * nx + ny * ny + nz * nz)
        if length < 1e-12:
            raise ValueError("degenerate polygon")
        n = (nx / length, ny / length, nz / length)
        cx = sum(q[0] for q in outer) / m
        cy = sum(q[1] for q in outer) / m
        cz = sum(q[2] for q in outer) / m
        self.n, self.d = n, n[0] * cx + n[1] * cy + n[2] * cz
        # An in-plane basis: u across the axis n is least aligned with, v = n x u.
        a = (1.0, 0.0, 0.0) if abs(n[0]) < 0.9 else (0.0, 1.0, 0.0)
        ux, uy, uz = (a[1] * n[2] - a[2] * n[1], a[2] * n[0] - a[0] * n[2],
                      a[0] * n[1] - a[1] * n[0])
        ul = math.sqrt(ux * ux + uy * uy + uz * uz)
        self.u = (ux / ul, uy / ul, uz / ul)
        u = self.u
        self.v = (n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0])
        self.rings2 = [[self._plane(q) for q in ring] for ring in rings]
        self.edges = []
        for ring in rings:
            k = len(ring)
            for i in range(k):
                a3, b3 = ring[i], ring[(i + 1) % k]
                e = (b3[0] - a3[0], b3[1] - a3[1], b3[2] - a3[2])
                ee = e[0] * e[0] + e[1] * e[1] + e[2] * e[2]
                if ee > 0.0:
                    self.edges.append((a3, e, ee))
        pts = [q for ring in rings for q in ring]
        self.lo = tuple(min(q[k] for q in pts) for k in range(3))
        self.hi = tuple(max(q[k] for q in pts) for k in range(3))

    def _plane(self, q):
        u, v = self.u, self.v
        return (u[0] * q[0] + u[1] * q[1] + u[2] * q[2], v[0] * q[0] + v[1] * q[1] + v[2] * q[2])

    def box_distance2(self, x, y, z):
        dx = max(self.lo[0] - x, 0.0, x - self.hi[0])
        dy = max(self.lo[1] - y, 0.0, y - self.hi[1])
        dz = max(self.lo[2] - z, 0.0, z - self.hi[2])
        return dx * dx + dy * dy + dz * dz

    def distance2(self, x, y, z):
        n = self.n
        s = n[0] * x + n[1] * y + n[2] * z - self.d
        pu, pv = self._plane((x, y, z))
        inside = False
        for ring in self.rings2:
            k = len(ring)
            au, av = ring[k - 1]
            for bu, bv in ring:
                if (av > pv) != (bv > pv) and pu < au + (pv - av) * (bu - au) / (bv - av):
                    inside = not inside
                au, av = bu, bv
        if inside:
            return s * s
        best = math.inf
        for a, e, ee in self.edges:
            wx, wy, wz = x - a[0], y - a[1], z - a[2]
            t = (wx * e[0] + wy * e[1] + wz * e[2]) / ee
            t = 0.0 if t < 0.0 else (1.0 if t > 1.0 else t)
            dx, dy, dz = wx - t * e[0], wy - t * e[1], wz - t * e[2]
            dd = dx * dx + dy * dy + dz * dz
            if dd < best:
                best = dd
        return best


def _surfaces_of(boundaries, depth, vertices, obj, out):
    """Appends the polygons of a boundary array of the given nesting depth (2: a surface)."""
    if depth == 2:
        rings = [[vertices[i] for i in ring] for ring in boundaries if len(ring) >= 3]
        if rings:
            try:
                out.append(Surface(obj, rings))
            except ValueError:
                pass
        return
    for b in boundaries:
        _surfaces_of(b, depth - 1, vertices, obj, out)


DEPTH = {"MultiSurface": 3, "CompositeSurface": 3, "Solid": 4, "MultiSolid": 5,
         "CompositeSolid": 5}


def read_model(paths):
    """Surfaces of the highest LoD of every feature in the CityJSONSeq files; also the count of
    features and of features by the LoD taken."""
    surfaces, lods = [], {}
    features = 0
    for path in paths:
        with open(path) as f:
            header = json.loads(f.readline())
            tr = header.get("transform", {"scale": [1, 1, 1], "translate": [0, 0, 0]})
            (sx, sy, sz), (tx, ty, tz) = tr["scale"], tr["translate"]
            for line in f:
                feat = json.loads(line)
                features += 1
                verts = [(x * sx + tx, y * sy + ty, z * sz + tz) for x, y, z in feat["vertices"]]
                geoms = [(oid, g) for oid, o in feat["CityObjects"].items()
                         for g in o.get("geometry", [])]

                def lod_key(g):
                    try:
                        return float(g.get("lod", "0"))
                    except ValueError:
                        return 0.0
                if not geoms:
                    continue
                top = max(lod_key(g) for _, g in geoms)
                lods[str(top)] = lods.get(str(top), 0) + 1
                for _, g in geoms:
                    if lod_key(g) == top and g.get("type") in DEPTH:
                        _surfaces_of(g["boundaries"], DEPTH[g["type"]], verts, feat["id"], surfaces)
    return surfaces, features, lods


def run_model(run_dir):
    """The CityJSONSeq files of a city run's cells."""
    return sorted(glob.glob(os.path.join(run_dir, "cells", "*", "model.city.jsonl")))


class Index:
    def __init__(self, surfaces):
        self.surfaces = surfaces
        self.bins = {}
        for k, s in enumerate(surfaces):
            for i in range(int(math.floor(s.lo[0] / CELL)), int(math.floor(s.hi[0] / CELL)) + 1):
                for j in range(int(math.floor(s.lo[1] / CELL)),
                               int(math.floor(s.hi[1] / CELL)) + 1):
                    self.bins.setdefault((i, j), []).append(k)

    def nearest(self, x, y, z):
        """(distance, surface index) of the nearest surface within SEARCH_LIMIT, else (inf, -1)."""
        ci, cj = int(math.floor(x / CELL)), int(math.floor(y / CELL))
        best, best_k = math.inf, -1
        seen = set()
        ring = 0
        while True:
            for i in range(ci - ring, ci + ring + 1):
                for j in range(cj - ring, cj + ring + 1):
                    if ring and abs(i - ci) != ring and abs(j - cj) != ring:
                        continue
                    for k in self.bins.get((i, j), ()):
                        if k in seen:
                            continue
                        seen.add(k)
                        s = self.surfaces[k]
                        if s.box_distance2(x, y, z) >= best:
                            continue
                        d = s.distance2(x, y, z)
                        if d < best:
                            best, best_k = d, k
            # Every surface closer than `reach` meets a cell searched so far.
            reach = min(x - (ci - ring) * CELL, (ci + ring + 1) * CELL - x,
                        y - (cj - ring) * CELL, (cj + ring + 1) * CELL - y)
            if best <= reach * reach or reach >= SEARCH_LIMIT:
                break
            ring += 1
        d = math.sqrt(best)
        return (d, best_k) if d <= SEARCH_LIMIT else (math.inf, -1)


def summarise(distances, objects=None):
    """Figures of a list of distances (inf: no surface within SEARCH_LIMIT)."""
    n = len(distances)
    if n == 0:
        return {"points": 0}
    out = {"points": n}
    for t in THRESHOLDS:
        out["within_%gm" % t] = sum(1 for d in distances if d <= t) / n
    capped = [min(d, SEARCH_LIMIT) for d in distances]
    out["rmse_m"] = math.sqrt(sum(d * d for d in capped) / n)
    s = sorted(capped)
    out["median_m"] = s[n // 2]
    out["covered"] = sum(1 for d in distances if d != math.inf) / n
    if objects is not None:
        per = {}
        for d, o in zip(distances, objects):
            if o is not None:
                per.setdefault(o, []).append(d * d)
        rmses = sorted(math.sqrt(sum(v) / len(v)) for v in per.values())
        if rmses:
            out["objects_with_points"] = len(rmses)
            out["object_rmse_median_m"] = rmses[len(rmses) // 2]
            out["objects_rmse_within_0.3m"] = sum(1 for r in rmses if r <= 0.3) / len(rmses)
    return out
