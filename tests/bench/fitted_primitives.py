"""The fitted primitives of a `csgtile fit --json` output in 2-D and 3-D (real_tiles.py):
their placements, point-to-surface distances and top-view outlines."""

import math

import top_surface  # beside this script


def placement(p):
    """(Q columns u, v, w as unit vectors, uniform scale s, translation t) of a 3x4 [R|t]."""
    m = p["placement"]
    cols = []
    for c in range(3):
        cols.append([m[r][c] for r in range(3)])
    s = math.sqrt(sum(v * v for v in cols[0]))
    if not s > 0:
        raise ValueError("primitive %s: degenerate placement" % p.get("id"))
    cols = [[v / s for v in col] for col in cols]
    t = [m[r][3] for r in range(3)]
    return cols, s, t


def to_local(frame, x, y, z):
    cols, s, t = frame
    dx, dy, dz = x - t[0], y - t[1], z - t[2]
    return ((cols[0][0] * dx + cols[0][1] * dy + cols[0][2] * dz) / s,
            (cols[1][0] * dx + cols[1][1] * dy + cols[1][2] * dz) / s,
            (cols[2][0] * dx + cols[2][1] * dy + cols[2][2] * dz) / s)


def to_world(frame, lx, ly, lz):
    cols, s, t = frame
    return tuple(t[r] + s * (cols[0][r] * lx + cols[1][r] * ly + cols[2][r] * lz)
                 for r in range(3))


def seg_dist(px, py, ax, ay, bx, by):
    ex, ey = bx - ax, by - ay
    ll = ex * ex + ey * ey
    u = 0.0 if ll == 0 else max(0.0, min(1.0, ((px - ax) * ex + (py - ay) * ey) / ll))
    dx, dy = px - ax - u * ex, py - ay - u * ey
    return math.sqrt(dx * dx + dy * dy)


inside_rings = top_surface.inside_rings  # even-odd over several rings (outer + holes)


def profile_distance(rho, z, profile, skip_axis):
    """Distance from (rho, z) to a closed profile's edges; edges on the axis (rho = 0) skipped."""
    best = math.inf
    n = len(profile)
    for i in range(n):
        a, b = profile[i], profile[(i + 1) % n]
        if skip_axis and abs(a[0]) < 1e-12 and abs(b[0]) < 1e-12:
            continue
        best = min(best, seg_dist(rho, z, a[0], a[1], b[0], b[1]))
    return best


class Primitive:
    """One fitted primitive: surface distance, XY footprint rings, bounding box (fit frame)."""

    def __init__(self, p):
        self.p = p
        self.type = p["type"]
        self.frame = placement(p)
        self.s = self.frame[1]
        self.id = p.get("id", "")
        # Half-spaces n·p <= w of the local frame the solid is cut by (a roof part).
        self.clips = [tuple(float(v) for v in c) for c in p.get("clip", [])]
        t = self.type
        if t == "box":
            self.size = [float(v) for v in p["size"]]
        elif t == "cylinder":
            self.profile = [(0.0, 0.0), (p["r"], 0.0), (p["r"], p["h"]), (0.0, p["h"])]
        elif t == "cone":
            self.profile = [(0.0, 0.0), (p["r1"], 0.0), (p["r2"], p["h"]), (0.0, p["h"])]
        elif t == "revolution":
            self.profile = [tuple(q) for q in p["profile"]]
        elif t == "extrusion":
            self.rings = [[tuple(q) for q in p["profile"]]] + \
                [[tuple(q) for q in h] for h in p.get("holes", [])]
            self.h = float(p["h"])
        elif t not in ("sphere", "torus"):
            raise ValueError("primitive %s: unknown type %s" % (self.id, t))
        pts = self.samples()
        self.lo = [min(q[i] for q in pts) for i in range(3)]
        self.hi = [max(q[i] for q in pts) for i in range(3)]

    # Points on (or bounding) the solid in the fit frame: corners, circles.
    def samples(self, n=64):
        p, fr, t = self.p, self.frame, self.type
        out = []

        def circle(r, z):
            for k in range(n):
                a = 2 * math.pi * k / n
                rr = r / math.cos(math.pi / n)  # circumscribed polygon: the hull covers the disc
                out.append(to_world(fr, rr * math.cos(a), rr * math.sin(a), z))
        if t == "box":
            dx, dy, dz = self.size
            for cx in (0, dx):
                for cy in (0, dy):
                    for cz in (0, dz):
                        out.append(to_world(fr, cx, cy, cz))
        elif t in ("cylinder", "cone", "revolution"):
            for rho, z in self.profile:
                circle(rho, z)
        elif t == "sphere":
            r = p["r"]
            for z in (-r, r):
                circle(r, z)  # the two caps' circles bound the sphere's box and hull
            circle(r, 0.0)
        elif t == "torus":
            big, small = p["R"], p["r"]
            for z in (-small, small):
                circle(big + small, z)
        elif t == "extrusion":
            for ring in self.rings:
                for x, y in ring:
                    out.append(to_world(fr, x, y, 0.0))
                    out.append(to_world(fr, x, y, self.h))
        return out

    def distance(self, x, y, z):
        """Unsigned distance from a fit-frame point to the solid's boundary."""
        lx, ly, lz = to_local(self.frame, x, y, z)
        t = self.type
        if t == "box":
            q = [abs(v - h / 2) - h / 2 for v, h in zip((lx, ly, lz), self.size)]
            outside = math.sqrt(sum(max(v, 0.0) ** 2 for v in q))
            d = outside + min(max(q), 0.0)
        elif t in ("cylinder", "cone", "revolution"):
            d = profile_distance(math.hypot(lx, ly), lz, self.profile, True)
        elif t == "sphere":
            d = math.sqrt(lx * lx + ly * ly + lz * lz) - self.p["r"]
        elif t == "torus":
            d = math.hypot(math.hypot(lx, ly) - self.p["R"], lz) - self.p["r"]
        else:  # extrusion
            d2 = math.inf
            for ring in self.rings:
                d2 = min(d2, profile_distance(lx, ly, ring, False))
            if inside_rings(lx, ly, self.rings):
                d2 = -d2
            dz = max(-lz, lz - self.h)
            if d2 <= 0 and dz <= 0:
                d = max(d2, dz)
            else:
                d = math.hypot(max(d2, 0.0), max(dz, 0.0))
        for nx, ny, nz, w in self.clips:  # the intersection: the larger signed distance
            d = max(d, nx * lx + ny * ly + nz * lz - w)
        return abs(d) * self.s

    def footprint(self):
        """XY projection as a list of shapes, each a list of rings filled even-odd."""
        t, fr = self.type, self.frame
        axis_vertical = abs(fr[0][2][2]) > 0.999
        if t == "torus" and axis_vertical:
            c = fr[2]
            big, small = self.p["R"] * self.s, self.p["r"] * self.s
            rings = [circle_ring(c[0], c[1], big + small)]
            if big > small:
                rings.append(circle_ring(c[0], c[1], big - small))
            return [rings]
        if t == "extrusion":
            shapes = []
            for z in (0.0, self.h):
                shapes.append([[to_world(fr, x, y, z)[:2] for x, y in ring]
                               for ring in self.rings])
            if not axis_vertical:
                for ring in self.rings:
                    for i in range(len(ring)):
                        a, b = ring[i], ring[(i + 1) % len(ring)]
                        quad = [to_world(fr, q[0], q[1], z)[:2]
                                for q, z in ((a, 0.0), (b, 0.0), (b, self.h), (a, self.h))]
                        shapes.append([convex_hull(quad)])
            return shapes
        return [[convex_hull([q[:2] for q in self.samples()])]]


def circle_ring(cx, cy, r, n=64):
    rr = r / math.cos(math.pi / n)
    return [(cx + rr * math.cos(2 * math.pi * k / n), cy + rr * math.sin(2 * math.pi * k / n))
            for k in range(n)]


def convex_hull(points):
    pts = sorted(set(points))
    if len(pts) <= 2:
        return pts

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    lower, upper = [], []
    for q in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], q) <= 0:
            lower.pop()
        lower.append(q)
    for q in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], q) <= 0:
            upper.pop()
        upper.append(q)
    return lower[:-1] + upper[:-1]


def ring_area(ring):
    a = 0.0
    for i in range(len(ring)):
        x0, y0 = ring[i]
        x1, y1 = ring[(i + 1) % len(ring)]
        a += x0 * y1 - x1 * y0
    return abs(a) / 2
