#!/usr/bin/env python3
"""`csgtile fit` on real LIDAR tiles, measured (issue #6, "Real data").

Usage: real_tiles.py CSGTILE OUT_DIR [--data DIR] [--tiles delft,ams,sample_c] [--use-footprints] [--unclassified | --ground-only]
                     [--config C] [--sigma S] [--cell 0.25] [--pixel 2]
                     [--min-share TILE=V ...] [--min-iou TILE=V ...]
                     [--min-top-within TILE=V ...] [--min-top-coverage TILE=V ...]
                     [--min-median-iou TILE=V ...] [--min-primitives TILE=N ...]
                     [--max-below-ground TILE=N ...]
                     (exit 1 below a threshold, 77 when no tile is present: CLI tests)
       real_tiles.py CSGTILE OUT_DIR --self-test   (the script's own geometry on known answers)

For each tile present under DIR (default: ../shared/data beside the repository):
  delft     3dfier/ahn3_cropped_2.las (AHN3, EPSG:28992, no CRS record: --crs EPSG:28992),
            footprints 3dfier/bgt_pand.sqlite (layer buildingpart, read with GDAL's ogr2ogr)
  ams       ams/ahn_2386_9702.las (AHN, EPSG:28992), footprints ams/bgt_buildings_demo.csv
  sample_c  pdal/sample_c.las (PDAL test data, no CRS: lengths in the file's unknown unit),
            no footprints
it runs `CSGTILE fit TILE --out OUT_DIR/<tile>_fit.json --json [--config C] [--crs ...]` and
reports:
  - the fit's counts per type, unassigned points, rejection reasons and timings (its --json);
  - building points (LAS class 6) within 2σ of a fitted primitive's surface, and within the
    fit's RANSAC epsilon and 0.25 / 0.5 / 1 m for context. σ = --sigma (default 0.05 m:
    AHN3's nominal stochastic error, 1σ). Distances are exact point-to-boundary distances of
    each primitive's solid (box, cylinder, cone, sphere, torus, extrusion, revolution — a
    revolution with angle < 2π is taken as a full one), computed in the fit's frame: the
    scene's `origin` (the LAS offset) is subtracted from the LAS points;
  - primitives_on_buildings: primitives most of whose nearby non-ground points (within 2σ,
    nearest to them) are building points; primitives_elsewhere: the others, by type;
  - primitives_below_ground: primitives whose lowest point is more than 0.5 m under the lowest
    ground point (class 2) near them;
  - footprint overlap (tiles with footprints): modelled footprints = union of the primitives'
    XY projections (exact convex hulls for box, cylinder, cone, sphere; annulus or hull for a
    torus; base ∪ top ∪ swept edges for an extrusion; hull of the profile circles for a
    revolution), published ones = the footprint polygons, both rasterised on a --cell grid
    (cell centres) and restricted to the tile's extent (2 m blocks holding at least one
    point). The footprint files are crops smaller than the tiles: `iou` (with precision and
    recall) counts only cells inside the footprint layer's bounding box, `iou_whole_tile` all
    of the tile's extent. The crops also miss buildings inside their bounding box:
    `iou_matched` sets aside the model's connected pieces there that meet no published
    footprint (`unmatched_model_components`, `unmatched_model_m2`). Per building: each model cell outside every footprint is given to
    the nearest footprint within 3 m (4-connected steps), and building b's IoU =
    |M ∩ B| / (|B| + |M_b \\ B|); buildings with at least half of their polygon area inside
    the extent are evaluated (median IoU, share with IoU >= 0.5);
  - a top view OUT_DIR/<tile>_top.png (--pixel pixels per cell, north up): points grey by
    height (darker = lower), primitives' footprints tinted by type (box orange, cylinder
    blue, cone green, sphere magenta, torus cyan, extrusion yellow, revolution purple),
    building points farther than 2σ from every primitive black, published footprints
    outlined red.
Prints one JSON object: {"sigma_m", "tiles": {name: figures}, "missing", "failures"}.

The figures of issue #6's closing note (build dir B, from the repository root):
  python3 tests/bench/real_tiles.py B/csgtile /tmp/real_tiles
  python3 tests/bench/real_tiles.py B/csgtile /tmp/real_tiles_air \\
      --config tests/bench/fit_airborne.yaml
With --use-footprints, csgtile fit gets the tile's footprints (--footprints; the Amsterdam CSV
written out as GeoJSON first): the figures inside the footprints are then those of issue #18's
runs with footprints (footprint IoU then says how exactly buildings stand on them).
(--config with any csgtile config for a sweep; --sigma 0.1 for a looser σ.)
Standard library only (struct + zlib for the PNG); GDAL's ogr2ogr for the SQLite footprints.
"""
import argparse
import json
import math
import os
import struct
import subprocess
import sys
import time
import zlib
from array import array
from collections import deque

from fitted_primitives import (Primitive, circle_ring, convex_hull, inside_rings, placement,
                               profile_distance, ring_area, seg_dist, to_local,
                               to_world)  # beside this script
import top_surface  # beside this script

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_DATA = os.path.normpath(os.path.join(HERE, "..", "..", "..", "shared", "data"))

TILES = {
    "delft": {"las": "3dfier/ahn3_cropped_2.las", "crs": "EPSG:28992",
              "footprints": ("sqlite", "3dfier/bgt_pand.sqlite", "buildingpart")},
    "ams": {"las": "ams/ahn_2386_9702.las", "crs": "EPSG:28992",
            "footprints": ("csv", "ams/bgt_buildings_demo.csv", None)},
    "sample_c": {"las": "pdal/sample_c.las", "crs": None, "footprints": None},
}

TYPE_COLOURS = {
    "box": (255, 140, 0), "cylinder": (30, 110, 255), "cone": (0, 190, 60),
    "sphere": (230, 0, 230), "torus": (0, 220, 220), "extrusion": (240, 220, 0),
    "revolution": (140, 60, 220),
}
CONTEXT_THRESHOLDS = (0.25, 0.5, 1.0)
ATTRIBUTION_DISTANCE = 3.0  # metres: model cells outside footprints go to the nearest one within


# ----------------------------------------------------------------------------- LAS

def read_las(path):
    """Points (x, y, z lists in file coordinates) and classes of a LAS 1.0-1.4 file."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] != b"LASF":
        raise ValueError(path + ": not a LAS file")
    minor = data[25]
    data_offset = struct.unpack_from("<I", data, 96)[0]
    fmt = data[104] & 0x3F
    rec = struct.unpack_from("<H", data, 105)[0]
    count = struct.unpack_from("<I", data, 107)[0]
    scale = struct.unpack_from("<3d", data, 131)
    offset = struct.unpack_from("<3d", data, 155)
    if minor >= 4 and count == 0:
        count = struct.unpack_from("<Q", data, 247)[0]
    if fmt <= 5:
        layout, cls_index, used = "<3iHBB", 5, 16
    else:
        layout, cls_index, used = "<3iHBBB", 6, 17
    if rec < used:
        raise ValueError(path + ": record length %d too short for format %d" % (rec, fmt))
    layout += "%dx" % (rec - used)
    end = data_offset + count * rec
    if end > len(data):
        raise ValueError(path + ": file ends before its %d points" % count)
    xs, ys, zs, cls = array("d"), array("d"), array("d"), bytearray()
    sx, sy, sz = scale
    ox, oy, oz = offset
    for r in struct.iter_unpack(layout, data[data_offset:end]):
        xs.append(r[0] * sx + ox)
        ys.append(r[1] * sy + oy)
        zs.append(r[2] * sz + oz)
        c = r[cls_index]
        cls.append(c & 0x1F if fmt <= 5 else c)
    return {"x": xs, "y": ys, "z": zs, "cls": cls, "format": fmt, "offset": offset}


# ----------------------------------------------------------------------------- raster

class Grid:
    def __init__(self, x0, y0, cell, nx, ny):
        self.x0, self.y0, self.cell, self.nx, self.ny = x0, y0, cell, nx, ny

    def fill(self, rings, visit):
        """Calls visit(index) for every cell whose centre lies inside the rings (even-odd)."""
        ys = [q[1] for ring in rings for q in ring]
        if not ys:
            return
        c = self.cell
        j0 = max(0, int(math.floor((min(ys) - self.y0) / c - 0.5)))
        j1 = min(self.ny - 1, int(math.ceil((max(ys) - self.y0) / c - 0.5)))
        edges = []
        for ring in rings:
            n = len(ring)
            for i in range(n):
                a, b = ring[i], ring[(i + 1) % n]
                if a[1] != b[1]:
                    edges.append((a[0], a[1], b[0], b[1]))
        for j in range(j0, j1 + 1):
            yc = self.y0 + (j + 0.5) * c
            xs = []
            for ax, ay, bx, by in edges:
                if (ay > yc) != (by > yc):
                    xs.append(ax + (yc - ay) * (bx - ax) / (by - ay))
            xs.sort()
            for k in range(0, len(xs) - 1, 2):
                i0 = max(0, int(math.ceil((xs[k] - self.x0) / c - 0.5)))
                i1 = min(self.nx - 1, int(math.ceil((xs[k + 1] - self.x0) / c - 0.5)) - 1)
                base = j * self.nx
                for i in range(i0, i1 + 1):
                    visit(base + i)

    def line(self, a, b, visit):
        length = math.hypot(b[0] - a[0], b[1] - a[1])
        steps = max(1, int(length / (self.cell / 3)))
        for k in range(steps + 1):
            x = a[0] + (b[0] - a[0]) * k / steps
            y = a[1] + (b[1] - a[1]) * k / steps
            i = int(math.floor((x - self.x0) / self.cell))
            j = int(math.floor((y - self.y0) / self.cell))
            if 0 <= i < self.nx and 0 <= j < self.ny:
                visit(j * self.nx + i)


def write_png(path, width, height, rgb):
    """Truecolor 8-bit PNG; rgb is a bytearray of width*height*3, first row = top."""
    raw = bytearray()
    stride = width * 3
    for r in range(height):
        raw.append(0)
        raw += rgb[r * stride:(r + 1) * stride]

    def chunk(kind, body):
        c = struct.pack(">I", len(body)) + kind + body
        return c + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(bytes(raw), 9)))
        f.write(chunk(b"IEND", b""))


# ----------------------------------------------------------------------------- footprints

def read_footprints(kind, path, layer):
    """List of buildings, each a list of polygons, each a list of rings [(x, y), ...]."""
    if kind == "sqlite":
        out = subprocess.run(["ogr2ogr", "-f", "GeoJSON", "/vsistdout/", path, layer],
                             capture_output=True, text=True)
        if out.returncode != 0:
            raise RuntimeError("ogr2ogr on %s: %s" % (path, out.stderr.strip()))
        buildings = []
        for feat in json.loads(out.stdout)["features"]:
            g = feat.get("geometry") or {}
            if g.get("type") == "Polygon":
                polys = [g["coordinates"]]
            elif g.get("type") == "MultiPolygon":
                polys = g["coordinates"]
            else:
                continue
            buildings.append([[[tuple(q[:2]) for q in ring] for ring in poly] for poly in polys])
        return buildings
    import csv
    buildings = []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            ring = [tuple(q) for q in json.loads(row["polygon"])]
            buildings.append([[ring]])
    return buildings


# ----------------------------------------------------------------------------- one tile

def median(v):
    v = sorted(v)
    if not v:
        return None
    n = len(v)
    return v[n // 2] if n % 2 else (v[n // 2 - 1] + v[n // 2]) / 2


def write_unclassified(src, dst, keep_ground=False):
    """A copy of a LAS file with every point's class set to 1 (never classified, as unclassified
    tiles are): the fit then sees no classification; the measure still uses the original's.
    With keep_ground, ground (2) stays: a tile classified for its ground only."""
    b = bytearray(open(src, "rb").read())
    offset = struct.unpack_from("<I", b, 96)[0]
    fmt = b[104] & 0x3F
    length = struct.unpack_from("<H", b, 105)[0]
    count = struct.unpack_from("<I", b, 107)[0]
    if count == 0 and b[25] >= 4:
        count = struct.unpack_from("<Q", b, 247)[0]
    for i in range(count):
        p = offset + i * length
        if fmt < 6:
            if not (keep_ground and b[p + 15] & 0x1F == 2):
                b[p + 15] = (b[p + 15] & 0xE0) | 1
        elif not (keep_ground and b[p + 16] == 2):
            b[p + 16] = 1
    with open(dst, "wb") as f:
        f.write(b)


def run_fit(name, spec, args, out_dir):
    """Runs `csgtile fit` on the tile: (figures, scene) or (figures with "error", None)."""
    las_path = os.path.join(args.data, spec["las"])
    fit_path = os.path.join(out_dir, name + "_fit.json")
    fit_input = las_path
    if args.unclassified or args.ground_only:
        fit_input = os.path.join(out_dir, name + "_unclassified.las")
        write_unclassified(las_path, fit_input, keep_ground=args.ground_only)
    cmd = [args.csgtile, "fit", fit_input, "--out", fit_path, "--json"]
    if args.config:
        cmd += ["--config", args.config]
    if args.use_footprints and spec["footprints"]:
        kind, rel, layer = spec["footprints"]
        path = os.path.join(args.data, rel)
        if kind == "csv":
            # Not a layout GDAL reads: written out as GeoJSON in the tile's CRS (the 2008
            # GeoJSON "crs" member, which GDAL honours).
            path = os.path.join(out_dir, name + "_footprints.geojson")
            feats = [{"type": "Feature", "properties": {"id": "b%d" % i},
                      "geometry": {"type": "MultiPolygon",
                                   "coordinates": [[[list(q) for q in ring] for ring in poly]
                                                   for poly in b]}}
                     for i, b in enumerate(read_footprints(kind, os.path.join(args.data, rel),
                                                           layer))]
            with open(path, "w") as f:
                json.dump({"type": "FeatureCollection",
                           "crs": {"type": "name",
                                   "properties": {"name": "urn:ogc:def:crs:EPSG::28992"}},
                           "features": feats}, f)
        cmd += ["--footprints", path]
        if layer:
            cmd += ["--footprints-layer", layer]
    if spec["crs"]:
        cmd += ["--crs", spec["crs"]]
    res = {"las": las_path, "command": " ".join(cmd)}
    t0 = time.monotonic()
    try:
        run = subprocess.run(cmd, capture_output=True, text=True)
    except OSError as e:
        res["error"] = "cannot run %s: %s" % (cmd[0], e)
        return res, None
    res["exit"] = run.returncode
    res["wall_seconds"] = time.monotonic() - t0
    try:
        fit = json.loads(run.stdout)
    except ValueError:
        fit = {"error": "no JSON from csgtile fit (exit %d): %s"
                        % (run.returncode, run.stderr[-500:])}
    if run.returncode != 0 or fit.get("error"):
        res["error"] = fit.get("error") or "exit %d" % run.returncode
        return res, None
    for k in ("points", "ground_points", "outlier_points", "fitted_points", "assigned_points",
              "unassigned_points", "regions", "primitives", "per_type", "seconds"):
        res[k] = fit.get(k)
    reasons = {}
    for r in fit.get("rejected", []):
        key = r["reason"].split(" (")[0]
        reasons[key] = reasons.get(key, 0) + 1
    res["rejections"] = dict(sorted(reasons.items(), key=lambda kv: -kv[1]))
    with open(fit_path) as f:
        scene = json.load(f)
    res["frame"] = {"crs": scene.get("crs"), "origin": scene.get("origin", [0.0, 0.0, 0.0])}
    return res, scene


def bucket_range(lo, hi, size):
    return range(int(math.floor(lo / size)), int(math.floor(hi / size)) + 1)


def measure_distances(res, prims, pts, sigma, epsilon):
    """Building points' distances to the primitives; returns the unexplained points' mask."""
    xs, ys, zs, cls = pts
    reach = max(max(CONTEXT_THRESHOLDS), 2 * sigma, epsilon)
    bucket = 2.0  # metres: primitives indexed by the XY buckets their grown box meets
    index = {}
    for k, p in enumerate(prims):
        for bi in bucket_range(p.lo[0] - reach, p.hi[0] + reach, bucket):
            for bj in bucket_range(p.lo[1] - reach, p.hi[1] + reach, bucket):
                index.setdefault((bi, bj), []).append(k)
    thresholds = {"2sigma": 2 * sigma, "epsilon": epsilon}
    for t in CONTEXT_THRESHOLDS:
        thresholds["%gm" % t] = t
    within = {k: 0 for k in thresholds}
    building = 0
    unexplained = bytearray(len(xs))  # building points farther than 2σ from every primitive
    near_building = [0] * len(prims)  # per primitive: points within 2σ whose nearest it is
    near_other = [0] * len(prims)
    for i in range(len(xs)):
        c = cls[i]
        if c == 2:
            continue
        x, y, z = xs[i], ys[i], zs[i]
        best, best_k = math.inf, -1
        for k in index.get((int(math.floor(x / bucket)), int(math.floor(y / bucket))), ()):
            p = prims[k]
            if not (p.lo[2] - reach <= z <= p.hi[2] + reach):
                continue
            d = p.distance(x, y, z)
            if d < best:
                best, best_k = d, k
        if best <= 2 * sigma:
            if c == 6:
                near_building[best_k] += 1
            else:
                near_other[best_k] += 1
        if c != 6:
            continue
        building += 1
        if best > 2 * sigma:
            unexplained[i] = 1
        for key, t in thresholds.items():
            if best <= t:
                within[key] += 1
    res["building_points"] = building
    res["building_share"] = {
        key: (within[key] / building if building else None) for key in thresholds}
    res["building_share_thresholds_m"] = thresholds
    # A primitive is "on a building" when most non-ground points within 2σ of it (nearest it)
    # are building points; the others sit on vegetation, street furniture or unclassified points.
    off = [k for k in range(len(prims)) if near_other[k] >= near_building[k]]
    res["primitives_on_buildings"] = len(prims) - len(off)
    res["primitives_elsewhere"] = {}
    for k in off:
        t = prims[k].type
        res["primitives_elsewhere"][t] = res["primitives_elsewhere"].get(t, 0) + 1
    return unexplained


def measure_below_ground(res, prims, pts):
    """Primitives reaching more than 0.5 m below the lowest ground point (class 2) under their
    XY box grown by 2 m: solids that cut into the terrain."""
    xs, ys, zs, cls = pts
    gcell = 2.0
    ground_low = {}
    for i in range(len(xs)):
        if cls[i] == 2:
            key = (int(math.floor(xs[i] / gcell)), int(math.floor(ys[i] / gcell)))
            if zs[i] < ground_low.get(key, math.inf):
                ground_low[key] = zs[i]
    below = []
    for p in prims:
        g = min((ground_low.get((bi, bj), math.inf)
                 for bi in bucket_range(p.lo[0] - 2, p.hi[0] + 2, gcell)
                 for bj in bucket_range(p.lo[1] - 2, p.hi[1] + 2, gcell)), default=math.inf)
        if math.isfinite(g) and p.lo[2] < g - 0.5:
            below.append({"id": p.id, "type": p.type, "depth_m": round(g - p.lo[2], 2)})
    res["primitives_below_ground"] = below


class TileRaster:
    """The tile on a grid: extent, highest point, unexplained building points, model cells."""

    def __init__(self, pts, unexplained, prims, cell):
        xs, ys, zs, _ = pts
        x0 = math.floor(min(xs) / cell) * cell
        y0 = math.floor(min(ys) / cell) * cell
        nx = int(math.floor((max(xs) - x0) / cell)) + 1
        ny = int(math.floor((max(ys) - y0) / cell)) + 1
        self.grid = Grid(x0, y0, cell, nx, ny)
        self.nx, self.ny, self.cell = nx, ny, cell
        size = nx * ny
        block = max(1, int(round(2.0 / cell)))
        bnx, bny = (nx + block - 1) // block, (ny + block - 1) // block
        covered_block = bytearray(bnx * bny)
        self.top = array("d", [-math.inf]) * size
        self.missed = bytearray(size)
        for i in range(len(xs)):
            ci = min(nx - 1, int((xs[i] - x0) / cell))
            cj = min(ny - 1, int((ys[i] - y0) / cell))
            covered_block[(cj // block) * bnx + ci // block] = 1
            k = cj * nx + ci
            if zs[i] > self.top[k]:
                self.top[k] = zs[i]
            if unexplained[i]:
                self.missed[k] = 1
        self.extent = bytearray(size)
        for j in range(ny):
            for i in range(nx):
                self.extent[j * nx + i] = covered_block[(j // block) * bnx + i // block]
        self.model = bytearray(size)
        self.model_type = bytearray(size)  # 1 + index into TYPE_COLOURS' order
        type_names = list(TYPE_COLOURS)
        for p in prims:
            code = type_names.index(p.type) + 1

            def mark(k, code=code):
                if self.extent[k]:
                    self.model[k] = 1
                    self.model_type[k] = code
            for rings in p.footprint():
                self.grid.fill([[(q[0], q[1]) for q in ring] for ring in rings], mark)
        self.outline = bytearray(size)


def grid_neighbours(k, nx, ny):
    """The 4-neighbours of cell k (row-major, nx × ny) inside the grid."""
    i, j = k % nx, k // nx
    if i > 0:
        yield k - 1
    if i + 1 < nx:
        yield k + 1
    if j > 0:
        yield k - nx
    if j + 1 < ny:
        yield k + nx


def measure_footprints(res, raster, buildings, origin):
    """IoU of the modelled footprints with the published ones, overall and per building."""
    ox, oy = origin[0], origin[1]
    grid, nx, ny, cell = raster.grid, raster.nx, raster.ny, raster.cell
    size = nx * ny
    model, extent = raster.model, raster.extent
    owner = array("i", [-1]) * size
    areas = []
    for b, polys in enumerate(buildings):
        area = 0.0
        for poly in polys:
            local = [[(q[0] - ox, q[1] - oy) for q in ring] for ring in poly]
            area += ring_area(local[0]) - sum(ring_area(h) for h in local[1:])

            def own(k, b=b):
                owner[k] = b
            grid.fill(local, own)
            for ring in local:
                for i in range(len(ring)):
                    grid.line(ring[i], ring[(i + 1) % len(ring)],
                              lambda k: raster.outline.__setitem__(k, 1))
        areas.append(area)
    for k in range(size):
        if not extent[k]:
            owner[k] = -1
    # The footprint layers are crops: where the layer has no data, model cells are not false
    # positives. `iou` counts cells inside the layer's bounding box only; `iou_whole_tile`
    # counts every cell of the tile's extent.
    fx = [q[0] - ox for polys in buildings for poly in polys for ring in poly for q in ring]
    fy = [q[1] - oy for polys in buildings for poly in polys for ring in poly for q in ring]
    layer = bytearray(size)
    grid.fill([[(min(fx), min(fy)), (max(fx), min(fy)), (max(fx), max(fy)), (min(fx), max(fy))]],
              lambda k: layer.__setitem__(k, 1))
    res["footprint_layer_bbox"] = [min(fx) + ox, min(fy) + oy, max(fx) + ox, max(fy) + oy]
    counted = {}
    for label, mask in (("", layer), ("_whole_tile", None)):
        cells = [k for k in range(size) if mask is None or mask[k]]
        published = sum(1 for k in cells if owner[k] >= 0)
        modelled = sum(1 for k in cells if model[k])
        inter = sum(1 for k in cells if owner[k] >= 0 and model[k])
        counted[label] = (published, modelled, inter)
        union = published + modelled - inter
        res["compared_m2" + label] = sum(1 for k in cells if extent[k]) * cell * cell
        res["published_footprint_m2" + label] = published * cell * cell
        res["modelled_footprint_m2" + label] = modelled * cell * cell
        res["iou" + label] = inter / union if union else None
        res["footprint_precision" + label] = inter / modelled if modelled else None
        res["footprint_recall" + label] = inter / published if published else None

    # The crops also leave out buildings inside their bounding box (Delft's holds a block the
    # AHN classifies as building in its north-west corner): model components (4-connected
    # model cells inside the box) meeting no published footprint are set aside and reported,
    # and `iou_matched` is the IoU over the rest.
    unmatched, pieces = 0, 0
    seen = bytearray(size)
    for start in range(size):
        if not model[start] or not layer[start] or seen[start]:
            continue
        seen[start] = 1
        comp, touches, h = [start], False, 0
        while h < len(comp):
            k = comp[h]
            h += 1
            touches = touches or owner[k] >= 0
            for m in grid_neighbours(k, nx, ny):
                if model[m] and layer[m] and not seen[m]:
                    seen[m] = 1
                    comp.append(m)
        if not touches:
            unmatched += len(comp)
            pieces += 1
    published, modelled, inter = counted[""]
    union = published + modelled - unmatched - inter
    res["unmatched_model_components"] = pieces
    res["unmatched_model_m2"] = unmatched * cell * cell
    res["iou_matched"] = inter / union if union else None

    # Per building: model cells outside every footprint go to the nearest one within 3 m.
    zone = array("i", owner)
    steps = int(round(ATTRIBUTION_DISTANCE / cell))
    dist = array("i", [0 if owner[k] >= 0 else -1 for k in range(size)])
    queue = deque(k for k in range(size) if owner[k] >= 0)
    while queue:
        k = queue.popleft()
        if dist[k] >= steps:
            continue
        for m in grid_neighbours(k, nx, ny):
            if dist[m] < 0:
                dist[m] = dist[k] + 1
                zone[m] = zone[k]
                queue.append(m)
    cells_b = [0] * len(buildings)
    inter_b = [0] * len(buildings)
    extra_b = [0] * len(buildings)
    for k in range(size):
        b = owner[k]
        if b >= 0:
            cells_b[b] += 1
            if model[k]:
                inter_b[b] += 1
        elif model[k] and zone[k] >= 0:
            extra_b[zone[k]] += 1
    in_tile = [b for b in range(len(buildings)) if cells_b[b] > 0]
    evaluated = [b for b in in_tile if cells_b[b] * cell * cell >= 0.5 * areas[b]]
    ious = [inter_b[b] / (cells_b[b] + extra_b[b]) for b in evaluated]
    res["buildings"] = {
        "in_layer": len(buildings), "in_tile": len(in_tile), "evaluated": len(evaluated),
        "median_iou": median(ious),
        "share_iou_ge_0_5": (sum(1 for v in ious if v >= 0.5) / len(ious)) if ious else None,
        "modelled": sum(1 for b in evaluated if inter_b[b] > 0),
    }


def write_cells_png(path, nx, ny, px, colour_of):
    """A PNG of nx × ny cells, px × px pixels each, north up (row j = 0 at the bottom), cell
    (i, j) in colour_of(i, j); returns (width, height, rgb)."""
    width, height = nx * px, ny * px
    rgb = bytearray(width * height * 3)
    for j in range(ny):
        row = ny - 1 - j
        line = bytearray()
        for i in range(nx):
            line += bytes(colour_of(i, j)) * px
        for r in range(px):
            o = (row * px + r) * width * 3
            rgb[o:o + width * 3] = line
    write_png(path, width, height, rgb)
    return width, height, rgb


def write_top_view(path, raster, px):
    """The PNG described in the module docstring; returns (width, height, distinct colours)."""
    nx, ny, top, extent = raster.nx, raster.ny, raster.top, raster.extent
    zvals = [v for v in top if v != -math.inf]
    zlo, zhi = (min(zvals), max(zvals)) if zvals else (0.0, 1.0)
    shown = array("d", top)  # cells without a point of their own show their neighbours' height
    for j in range(ny):
        for i in range(nx):
            k = j * nx + i
            if top[k] != -math.inf or not extent[k]:
                continue
            for jj in (j - 1, j, j + 1):
                for ii in (i - 1, i, i + 1):
                    if 0 <= ii < nx and 0 <= jj < ny and top[jj * nx + ii] > shown[k]:
                        shown[k] = top[jj * nx + ii]
    colours = [None] + list(TYPE_COLOURS.values())

    def colour_of(i, j):
        k = j * nx + i
        if shown[k] == -math.inf:
            g = 255 if extent[k] else 235
        else:
            g = int(100 + 140 * (shown[k] - zlo) / max(zhi - zlo, 1e-9))
        c = (g, g, g)
        if raster.model_type[k]:
            t = colours[raster.model_type[k]]
            c = tuple(int(0.45 * c[q] + 0.55 * t[q]) for q in range(3))
        if raster.missed[k]:
            c = (0, 0, 0)
        if raster.outline[k]:
            c = (220, 0, 0)
        return c
    width, height, rgb = write_cells_png(path, nx, ny, px, colour_of)
    return width, height, len({bytes(rgb[o:o + 3]) for o in range(0, len(rgb), 3 * px)})


def footprint_test(buildings, origin):
    """inside(x, y) for fit-frame points: in any published footprint (bounding boxes first)."""
    ox, oy = origin[0], origin[1]
    polys = []
    for polys_of in buildings:
        for poly in polys_of:
            local = [[(q[0] - ox, q[1] - oy) for q in ring] for ring in poly]
            xs = [q[0] for q in local[0]]
            ys = [q[1] for q in local[0]]
            polys.append((min(xs), min(ys), max(xs), max(ys), local))

    def inside(x, y):
        return any(a <= x <= c and b <= y <= d and inside_rings(x, y, rings)
                   for a, b, c, d, rings in polys)
    return inside


def measure_tile(name, spec, args, out_dir):
    res, scene = run_fit(name, spec, args, out_dir)
    if scene is None:
        return res
    origin = res["frame"]["origin"]
    prims = [Primitive(p) for p in scene.get("primitives", [])]
    las = read_las(res["las"])
    ox, oy, oz = origin
    pts = (array("d", (v - ox for v in las["x"])), array("d", (v - oy for v in las["y"])),
           array("d", (v - oz for v in las["z"])), las["cls"])
    hist = {}
    for c in las["cls"]:
        hist[c] = hist.get(c, 0) + 1
    res["classes"] = {str(k): hist[k] for k in sorted(hist)}

    unexplained = measure_distances(res, prims, pts, args.sigma, fit_epsilon(args.csgtile, args.config))
    measure_below_ground(res, prims, pts)
    raster = TileRaster(pts, unexplained, prims, args.cell)
    res["extent_m2"] = sum(raster.extent) * args.cell ** 2
    res["model_footprint_m2"] = sum(raster.model) * args.cell ** 2
    buildings = []
    if spec["footprints"] and not args.no_footprints:
        kind, rel, layer = spec["footprints"]
        try:
            buildings = read_footprints(kind, os.path.join(args.data, rel), layer)
        except (OSError, RuntimeError, ValueError, KeyError) as e:
            res["footprints_error"] = "%s: %s" % (rel, e)
            buildings = []
        if buildings:
            measure_footprints(res, raster, buildings, origin)
        elif "footprints_error" not in res:
            res["footprints_error"] = "%s: no polygons" % rel
    inside = footprint_test(buildings, origin) if spec["footprints"] and not args.no_footprints \
        and buildings else None
    grid = {}
    res["top_surface"] = top_surface.measure_top_surface(prims, pts, args.top_cell, inside, grid)
    if inside is not None:
        res["top_surface"]["inside_footprints"]["footprints_as_model"] = \
            top_surface.footprints_as_model(inside, pts, args.top_cell, grid["x0"], grid["y0"],
                                            grid["nx"], grid["ny"])
    residual_png = os.path.join(out_dir, name + "_residuals.png")
    write_residual_view(residual_png, grid, args.pixel)
    res["residual_image"] = residual_png
    png = os.path.join(out_dir, name + "_top.png")
    width, height, distinct = write_top_view(png, raster, args.pixel)
    res["image"] = {"path": png, "width": width, "height": height, "colours": distinct,
                    "bytes": os.path.getsize(png), "metres_per_pixel": args.cell / args.pixel}
    return res


def write_residual_view(path, grid, px):
    """Top view of the issue #18 measure, one --top-cell per px pixels, north up: per cell the
    median of its building points' z - top of the model: white within 0.3 m, red where the
    points lie above the model (deeper up to 3 m), blue where the model is too high, black
    where building points have no model over them, yellow where the model covers no
    building point (false area), grey elsewhere."""
    nx, ny, tops, res = grid["nx"], grid["ny"], grid["tops"], grid.get("residuals", {})

    def colour_of(i, j):
        r = res.get((i, j))
        if r is None:
            return (230, 200, 40) if (i, j) in tops else (90, 90, 90)
        covered = sorted(v for v in r if v is not None)
        if not covered:
            return (0, 0, 0)
        m = covered[len(covered) // 2]
        depth = min(1.0, (abs(m) - 0.3) / 2.7) if abs(m) > 0.3 else 0.0
        fade = int(235 - 200 * depth)
        if depth == 0.0:
            return (250, 250, 250)
        return (235, fade, fade) if m > 0 else (fade, fade, 235)
    write_cells_png(path, nx, ny, px, colour_of)


def self_test():
    """Known answers for the distance, footprint and PNG code; returns a list of failures."""
    fails = []

    def rot_z(deg, t):
        c, s_ = math.cos(math.radians(deg)), math.sin(math.radians(deg))
        return [[c, -s_, 0, t[0]], [s_, c, 0, t[1]], [0, 0, 1, t[2]]]

    def tilted(t):  # axis +Z mapped to +X
        return [[0, 0, 1, t[0]], [0, -1, 0, t[1]], [1, 0, 0, t[2]]]

    def check(what, got, want, tol=1e-9):
        if not abs(got - want) <= tol:
            fails.append("%s: got %r, want %r" % (what, got, want))

    box = Primitive({"type": "box", "size": [2, 3, 4], "placement": rot_z(30, (5, 6, 7))})
    centre = to_world(box.frame, 1, 1.5, 2)
    check("box centre", box.distance(*centre), 1.0)
    check("box face", box.distance(*to_world(box.frame, 1, 0, 2)), 0.0)
    check("box corner", box.distance(*to_world(box.frame, 2.1, 3.1, 4.1)), math.sqrt(0.03))
    scaled = Primitive({"type": "box", "size": [1, 1, 1],
                        "placement": [[2, 0, 0, 0], [0, 2, 0, 0], [0, 0, 2, 0]]})
    check("scaled box", scaled.distance(3, 1, 1), 1.0)
    cyl = Primitive({"type": "cylinder", "r": 1, "h": 2, "placement": tilted((1, 2, 3))})
    check("cylinder axis", cyl.distance(*to_world(cyl.frame, 0, 0, 1)), 1.0)
    check("cylinder side", cyl.distance(*to_world(cyl.frame, 0.6, 0.8, 0.5)), 0.0)
    check("cylinder above", cyl.distance(*to_world(cyl.frame, 0, 0, 2.5)), 0.5)
    cone = Primitive({"type": "cone", "r1": 1, "r2": 0, "h": 1, "placement": rot_z(0, (0, 0, 0))})
    check("cone apex", cone.distance(0, 0, 1.5), 0.5)
    check("cone side", cone.distance(0.5, 0, 0.5), 0.0)
    sph = Primitive({"type": "sphere", "r": 2, "placement": rot_z(0, (1, 1, 1))})
    check("sphere centre", sph.distance(1, 1, 1), 2.0)
    tor = Primitive({"type": "torus", "R": 2, "r": 0.5, "placement": rot_z(0, (0, 0, 0))})
    check("torus tube", tor.distance(2, 0, 0), 0.5)
    check("torus centre", tor.distance(0, 0, 0), 1.5)
    ext = Primitive({"type": "extrusion", "h": 3, "placement": rot_z(90, (0, 0, 0)),
                     "profile": [[0, 0], [4, 0], [4, 1], [1, 1], [1, 4], [0, 4]]})
    check("extrusion inside", ext.distance(*to_world(ext.frame, 0.5, 2, 1.5)), 0.5)
    check("extrusion notch", ext.distance(*to_world(ext.frame, 2, 2, 1.5)), 1.0)
    check("extrusion above", ext.distance(*to_world(ext.frame, 0.5, 0.5, 4)), 1.0)
    rev = Primitive({"type": "revolution", "profile": [[0, 0], [1, 0], [1, 2], [0, 2]],
                     "placement": tilted((1, 2, 3))})
    for q in ((1.3, 2.2, 3.1), (0.2, 2.9, 3.4), (3.5, 2, 3)):
        check("revolution = cylinder at %s" % (q,), rev.distance(*q), cyl.distance(*q))

    grid = Grid(-5.0, -5.0, 0.25, 40, 40)
    for prim, area, tol in ((Primitive({"type": "box", "size": [4, 2, 1],
                                        "placement": rot_z(0, (-2, -1, 0))}), 8.0, 1e-9),
                            (Primitive({"type": "cylinder", "r": 1, "h": 1,
                                        "placement": rot_z(0, (0, 0, 0))}), math.pi, 0.15),
                            (tor, math.pi * (2.5 ** 2 - 1.5 ** 2), 0.4),
                            (ext, 7.0, 1e-9),
                            # the L lying on its side: its 4 x 3 bounding rectangle
                            (Primitive({"type": "extrusion", "h": 3,
                                        "placement": [[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0]],
                                        "profile": ext.p["profile"]}), 12.0, 1e-9)):
        cells = bytearray(40 * 40)
        for rings in prim.footprint():
            grid.fill(rings, lambda k: cells.__setitem__(k, 1))
        check("%s footprint area" % prim.type, sum(cells) * 0.0625, area, tol)

    # The top surface (top_surface.py): the highest z on the vertical through a point.
    def top(prim, x, y):
        z = top_surface.top_of(prim, x, y)
        return -1.0 if z is None else z
    check("top of box", top(box, *to_world(box.frame, 1, 1.5, 0)[:2]), 11.0)
    check("top beside box", top(box, 20, 20), -1.0)
    check("top of lying cylinder", top(cyl, 1.5, 2.6), 3.0 + 0.8)
    check("top of sphere", top(sph, 1, 1), 3.0, 2e-3)
    check("top of cone", top(cone, 0.5, 0), 0.5, 2e-3)
    # A shed roof part: the L under z = 6 + 0.5 x (clip n·p <= d in its frame).
    nn = math.sqrt(1.25)
    part = Primitive({"type": "extrusion", "h": 20, "placement": rot_z(0, (10, 20, -1)),
                      "profile": [[0, 0], [8, 0], [8, 4], [4, 4], [4, 10], [0, 10]],
                      "clip": [[-0.5 / nn, 0, 1 / nn, 7 / nn]]})
    check("top of roof part", top(part, 10 + 2, 20 + 1), -1 + 7 + 0.5 * 2)
    check("top over the L's notch", top(part, 10 + 6, 20 + 6), -1.0)
    check("roof part's roof distance", part.distance(12, 21, 7.0), 0.0, 1e-9)
    fig = top_surface.measure_top_surface(
        [box], ([c[0] for c in [to_world(box.frame, 1, 1.5, 4.1)]] + [30.0],
                [c[1] for c in [to_world(box.frame, 1, 1.5, 4.1)]] + [30.0],
                [11.1, 5.0], [6, 6]), 0.5)
    check("top-surface coverage", fig["whole_tile"]["coverage"], 0.5)
    # The footprint [0, 1.1] x [0, 1] as the model on a 0.5 m grid from the origin. Of its
    # points (0.1, 0.1), (0.9, 0.3) and (1.05, 0.2), the last lies in a cell whose centre
    # (1.25) is outside it: uncovered. (1.2, 0.2) lies outside it, (0.4, 1.2) is ground. Its
    # cells are the four of centres 0.25 and 0.75, of which two hold a building point.
    ref = top_surface.footprints_as_model(
        lambda x, y: 0.0 <= x <= 1.1 and 0.0 <= y <= 1.0,
        ([0.1, 0.9, 1.05, 1.2, 0.4], [0.1, 0.3, 0.2, 0.2, 1.2], [0.0] * 5, [6, 6, 6, 6, 2]),
        0.5, 0.0, 0.0, 4, 4)
    check("footprints as the model: coverage", ref["coverage"], 2 / 3)
    check("footprints as the model: false area", ref["false_area"], 2 / 4)
    check("top-surface within 0.3 m", fig["whole_tile"]["within_0.3m"], 0.5)
    check("top-surface rmse", fig["whole_tile"]["rmse_m"], 0.1, 1e-9)
    # A perfect model's share: one height per cell within 0.3 m of at most 3 of these 4
    # (a steep roof's spread), and of the one point of the other cell.
    best = top_surface.best_possible({(0, 0): [0.5, 0.0, 2.5, 0.1], (1, 0): [7.0]}, 5)
    check("best possible within 0.3 m", best["within_0.3m"], 4 / 5)
    check("best possible within 0.1 m", best["within_0.1m"], 3 / 5)
    check("best possible within 1 m", best["within_1m"], 4 / 5)

    # Footprint IoU on a 1 m grid of 10 x 4 cells: a published 4 x 2 m footprint, a model of
    # 5 x 2 m over it and a 2 x 2 m model piece apart from it that the crop does not hold.
    class Raster:
        pass
    r = Raster()
    r.nx, r.ny, r.cell = 10, 4, 1.0
    r.grid = Grid(0.0, 0.0, 1.0, 10, 4)
    r.extent = bytearray([1]) * 40
    r.model = bytearray(40)
    r.outline = bytearray(40)
    for j in (1, 2):
        for i in (1, 2, 3, 4, 5, 8, 9):
            r.model[j * 10 + i] = 1
    res = {}
    # (The second footprint, a sliver holding no cell centre, widens the crop's box to x = 10.)
    measure_footprints(res, r, [[[[(1, 1), (5, 1), (5, 3), (1, 3)]]],
                                [[[(9.9, 0), (10, 0), (10, 0.1)]]]], (0.0, 0.0, 0.0))
    check("footprint IoU", res["iou"], 8 / 14)
    check("footprint IoU over the crop's buildings", res["iou_matched"], 8 / 10)
    check("model pieces the crop does not hold", res["unmatched_model_m2"], 4.0)

    path = os.path.join(os.environ.get("TMPDIR", "/tmp"),
                        "real_tiles_self_test_%d.png" % os.getpid())
    write_png(path, 2, 1, bytearray([255, 0, 0, 0, 0, 255]))
    with open(path, "rb") as f:
        png = f.read()
    os.remove(path)
    idat = png.index(b"IDAT")
    size = struct.unpack(">I", png[idat - 4:idat])[0]
    if png[:8] != b"\x89PNG\r\n\x1a\n" or \
            zlib.decompress(png[idat + 4:idat + 4 + size]) != b"\x00\xff\x00\x00\x00\x00\xff":
        fails.append("PNG writer: wrong signature or pixel data")
    return fails


def fit_epsilon(csgtile, config):
    """fit.ransac.epsilon of the config as csgtile reads it (validate-config), else the default."""
    eps = 0.02  # fit::RansacOptions default
    if config:
        p = subprocess.run([csgtile, "validate-config", "--no-input-check", "--json", config],
                           capture_output=True, text=True)
        eps = json.loads(p.stdout)["config"]["fit"]["ransac"]["epsilon"]
    return eps


def parse_limits(items, kind):
    out = {}
    for item in items or []:
        tile, _, value = item.partition("=")
        if tile not in TILES or not value:
            raise SystemExit("--%s %s: expected TILE=VALUE with TILE one of %s"
                             % (kind, item, ", ".join(TILES)))
        out[tile] = float(value)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("csgtile")
    ap.add_argument("out_dir")
    ap.add_argument("--data", default=DEFAULT_DATA)
    ap.add_argument("--tiles", default=",".join(TILES))
    ap.add_argument("--config", help="csgtile config (YAML, fit: section) given to csgtile fit --config")
    ap.add_argument("--unclassified", action="store_true",
                    help="fit a copy of each tile with its classes cleared (an unclassified "
                         "tile: ground, vegetation and buildings from the geometry alone); the "
                         "measure keeps the original classes")
    ap.add_argument("--ground-only", action="store_true",
                    help="fit a copy of each tile with every class but ground (2) set to 1 (a "
                         "tile classified for its ground only: vegetation and buildings from the "
                         "geometry); the measure keeps the original classes")
    ap.add_argument("--use-footprints", action="store_true",
                    help="give csgtile fit the tile's published footprints (--footprints): one "
                         "building per footprint")
    ap.add_argument("--sigma", type=float, default=0.05,
                    help="σ in metres (default 0.05: AHN3's nominal stochastic error)")
    ap.add_argument("--cell", type=float, default=0.25)
    ap.add_argument("--top-cell", type=float, default=0.5,
                    help="grid of the top-surface figures (issue #18: 0.5 m)")
    ap.add_argument("--pixel", type=int, default=2, help="image pixels per cell edge")
    ap.add_argument("--no-footprints", action="store_true")
    ap.add_argument("--min-share", action="append", help="TILE=V: building share within 2σ")
    ap.add_argument("--min-top-within", action="append",
                    help="TILE=V: building points within 0.3 m of the model's top (inside the "
                         "footprints when the tile has them, else the whole tile)")
    ap.add_argument("--min-top-coverage", action="append",
                    help="TILE=V: building points over the model (same scope)")
    ap.add_argument("--min-iou", action="append", help="TILE=V: footprint IoU")
    ap.add_argument("--min-median-iou", action="append", help="TILE=V: median per-building IoU")
    ap.add_argument("--min-primitives", action="append", help="TILE=N")
    ap.add_argument("--max-below-ground", action="append",
                    help="TILE=N: primitives reaching more than 0.5 m under the ground")
    ap.add_argument("--self-test", action="store_true",
                    help="check the distance, footprint and PNG code on known answers, then exit")
    args = ap.parse_args()
    if args.self_test:
        fails = self_test()
        for f in fails:
            print("real_tiles: self-test FAIL: " + f, file=sys.stderr)
        print(json.dumps({"self_test": "fail" if fails else "pass", "failures": fails}))
        return 1 if fails else 0
    limits = {"building_share_2sigma": parse_limits(args.min_share, "min-share"),
              "top_within_0.3m": parse_limits(args.min_top_within, "min-top-within"),
              "top_coverage": parse_limits(args.min_top_coverage, "min-top-coverage"),
              "iou": parse_limits(args.min_iou, "min-iou"),
              "median_iou": parse_limits(args.min_median_iou, "min-median-iou"),
              "primitives": parse_limits(args.min_primitives, "min-primitives")}
    if not os.path.isdir(args.data):
        print(json.dumps({"skipped": "no data folder %s" % args.data}))
        return 77
    os.makedirs(args.out_dir, exist_ok=True)
    names = [t for t in args.tiles.split(",") if t]
    for t in names:
        if t not in TILES:
            raise SystemExit("--tiles: unknown tile %s (known: %s)" % (t, ", ".join(TILES)))
    report = {"sigma_m": args.sigma,
              "sigma_is": "AHN3 nominal stochastic error (1σ); --sigma to change",
              "config": args.config, "cell_m": args.cell, "tiles": {}, "missing": [],
              "failures": []}
    for name in names:
        spec = TILES[name]
        needed = [spec["las"]] + ([spec["footprints"][1]] if spec["footprints"] else [])
        absent = [p for p in needed if not os.path.exists(os.path.join(args.data, p))]
        if absent:
            report["missing"].append({"tile": name, "absent": absent})
            print("real_tiles: %s not measured (absent under %s: %s); its thresholds are not "
                  "checked" % (name, args.data, ", ".join(absent)), file=sys.stderr)
            continue
        res = measure_tile(name, spec, args, args.out_dir)
        report["tiles"][name] = res
        if "error" in res:
            report["failures"].append("%s: csgtile fit failed: %s" % (name, res["error"]))
            continue
        top = res["top_surface"].get("inside_footprints") or res["top_surface"]["whole_tile"]
        got = {"building_share_2sigma": res["building_share"]["2sigma"],
               "top_within_0.3m": top.get("within_0.3m"),
               "top_coverage": top.get("coverage"),
               "iou": res.get("iou"),
               "median_iou": res.get("buildings", {}).get("median_iou"),
               "primitives": res["primitives"]}
        for key, per_tile in limits.items():
            if name in per_tile and (got[key] is None or got[key] < per_tile[name]):
                report["failures"].append("%s: %s %s below %s"
                                          % (name, key, got[key], per_tile[name]))
        below = parse_limits(args.max_below_ground, "max-below-ground")
        if name in below and len(res["primitives_below_ground"]) > below[name]:
            report["failures"].append("%s: %d primitives below the ground (at most %g)"
                                      % (name, len(res["primitives_below_ground"]), below[name]))
        if "footprints_error" in res:
            report["failures"].append("%s: no footprints: %s" % (name, res["footprints_error"]))
        image = res["image"]
        with open(image["path"], "rb") as f:
            head = f.read(8)
        if head != b"\x89PNG\r\n\x1a\n" or image["bytes"] < 1000 or image["colours"] < 8:
            report["failures"].append("%s: top view %s is trivial (%d bytes, %d colours)"
                                      % (name, image["path"], image["bytes"], image["colours"]))
    print(json.dumps(report, indent=1))
    if not report["tiles"]:
        print("real_tiles: SKIP: none of the tiles is present under %s" % args.data,
              file=sys.stderr)
        return 77
    for f in report["failures"]:
        print("real_tiles: FAIL: " + f, file=sys.stderr)
    return 1 if report["failures"] else 0


if __name__ == "__main__":
    sys.exit(main())
