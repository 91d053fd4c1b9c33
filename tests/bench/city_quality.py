#!/usr/bin/env python3
"""Quality of the city models `csgtile run` publishes on the shared real tiles, measured as
3DBAG measures its LoD2.2 (issue #18): each building point's 3D distance to the published
model (model_distance.py).

For each tile present — Delft (laz/ahn3_cropped_2.laz, points read from its LAS reference
3dfier/ahn3_cropped_2.las; footprints 3dfier/bgt_pand.sqlite) and Amsterdam
(ams/ahn_2386_9702.las, footprints ams/bgt_buildings_demo.csv) — it runs `csgtile run` with
default settings (city_speed.py's configuration, one thread), without and with the footprints,
reads what the cells published (model.city.jsonl: the highest LoD of each feature) and gives,
for the class-6 points inside the BGT footprints and for all class-6 points of the tile:
share within 0.1 / 0.3 / 1 m, RMSE, median, covered (a surface within 20 m) and the median of
the published objects' RMSEs (points given to the object of their nearest surface); and the
buildings as instances (`instances`: a footprint and an object match when their building
points' IoU is at least 0.5; recall over the footprints, precision over the objects). A top
view OUT/<run>_distance.png (0.5 m pixels, north up): the farthest building point of each
pixel white within 0.3 m, orange within 1 m, red farther, black with no surface near; other
points grey; footprints outlined blue.

With --split SIZE the tile is first cut by `csgtile tile` into LAS tiles of SIZE metres and
the run reads their directory (a run of several tiles: buildings across tile edges must come
out as from the whole tile); the runs are named <tile>_<mode>_split<SIZE>. With
--split-points N (and --cell-size S, --halo H) the run fits the tile in blocks of cells of
about N points (city.split_points), each fit job streaming the file for its block and halo;
the runs are named <tile>_<mode>_points<N>.

Usage: city_quality.py CSGTILE WORK_DIR [--data DIR] [--tiles delft,ams] [--runs derived,footprints]
                       [--split SIZE] [--split-points N --cell-size S --halo H]
                       [--min-within RUN=V ...] [--max-rmse RUN=V ...]
Prints one JSON object. With --min-within / --max-rmse (RUN e.g. delft_footprints: the share
within 0.3 m and the RMSE inside the footprints), exit 1 when a run misses its bound (a CLI
test). Exit 77 when no tile is present. Standard library only.
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import time

import city_speed  # beside this script
import model_distance
from real_tiles import Grid, read_footprints, read_las, write_png

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_DATA = os.path.normpath(os.path.join(HERE, "..", "..", "..", "shared", "data"))
TILES = {
    "delft": {"run_input": "laz/ahn3_cropped_2.laz", "las": "3dfier/ahn3_cropped_2.las",
              "footprints": ("sqlite", "3dfier/bgt_pand.sqlite", "buildingpart")},
    "ams": {"run_input": "ams/ahn_2386_9702.las", "las": "ams/ahn_2386_9702.las",
            "footprints": ("csv", "ams/bgt_buildings_demo.csv", "")},
}
PIXEL = 0.5


def footprint_mask(grid, buildings):
    mask = bytearray(grid.nx * grid.ny)

    def mark(k):
        mask[k] = 1
    for polys in buildings:
        for poly in polys:
            grid.fill(poly, mark)
    return mask


def instances(pairs, in_footprint, of_object, least=10):
    """Buildings as instances, the way segmentations are scored: a footprint (with at least
    `least` building points) and a published object match when their building points' IoU
    (points inside the footprint given to the object of their nearest surface, over the union
    of the footprint's points and the object's) is at least 0.5 — one to one by construction.
    Recall over the footprints, precision over the objects holding at least `least` points."""
    footprints = [b for b, n in enumerate(in_footprint) if n >= least]
    objects = [o for o, n in of_object.items() if n >= least]
    matched, ious = 0, []
    for (b, o), n in pairs.items():
        iou = n / (in_footprint[b] + of_object[o] - n)
        if iou >= 0.5 and in_footprint[b] >= least:
            matched += 1
            ious.append(iou)
    return {"footprints": len(footprints), "objects": len(objects), "matched": matched,
            "recall": round(matched / max(1, len(footprints)), 3),
            "precision": round(matched / max(1, len(objects)), 3),
            "mean_iou_matched": round(sum(ious) / max(1, len(ious)), 3)}


def measure(points, buildings, model_paths, picture):
    surfaces, features, lods = model_distance.read_model(model_paths)
    index = model_distance.Index(surfaces)
    xs, ys, zs, cls = points["x"], points["y"], points["z"], points["cls"]
    x0 = math.floor(min(xs) / PIXEL) * PIXEL
    y0 = math.floor(min(ys) / PIXEL) * PIXEL
    nx = int((max(xs) - x0) / PIXEL) + 1
    ny = int((max(ys) - y0) / PIXEL) + 1
    grid = Grid(x0, y0, PIXEL, nx, ny)
    mask = footprint_mask(grid, buildings)
    label = [-1] * (nx * ny)  # the footprint of each pixel (the last one drawn)
    for b, polys in enumerate(buildings):
        def mark(k, b=b):
            label[k] = b
        for poly in polys:
            grid.fill(poly, mark)
    pairs = {}  # (footprint, object) -> building points in both
    in_footprint = [0] * len(buildings)
    of_object = {}
    worst = [-1.0] * (nx * ny)   # farthest building point per pixel (inf: no surface)
    other = bytearray(nx * ny)
    all_d, all_o, in_d, in_o = [], [], [], []
    for i in range(len(xs)):
        k = min(ny - 1, int((ys[i] - y0) / PIXEL)) * nx + min(nx - 1, int((xs[i] - x0) / PIXEL))
        if cls[i] != 6:
            other[k] = 1
            continue
        d, s = index.nearest(xs[i], ys[i], zs[i])
        o = surfaces[s].obj if s >= 0 else None
        all_d.append(d)
        all_o.append(o)
        if o is not None:
            of_object[o] = of_object.get(o, 0) + 1
        if label[k] >= 0:
            in_footprint[label[k]] += 1
            if o is not None:
                pairs[(label[k], o)] = pairs.get((label[k], o), 0) + 1
        if mask[k]:
            in_d.append(d)
            in_o.append(o)
        if d > worst[k]:
            worst[k] = d
    rgb = bytearray(nx * ny * 3)
    for j in range(ny):
        for i in range(nx):
            k = j * nx + i
            w = worst[k]
            if w < 0:
                c = (200, 200, 200) if other[k] else (110, 110, 110)
            elif w == math.inf:
                c = (0, 0, 0)
            elif w <= 0.3:
                c = (255, 255, 255)
            elif w <= 1.0:
                c = (255, 150, 0)
            else:
                c = (220, 0, 0)
            p = ((ny - 1 - j) * nx + i) * 3
            rgb[p:p + 3] = bytes(c)

    def outline(k):
        j, i = divmod(k, nx)
        p = ((ny - 1 - j) * nx + i) * 3
        rgb[p:p + 3] = bytes((40, 90, 255))
    for polys in buildings:
        for poly in polys:
            for ring in poly:
                for a in range(len(ring)):
                    grid.line(ring[a], ring[(a + 1) % len(ring)], outline)
    write_png(picture, nx, ny, rgb)
    return {"features": features, "instances": instances(pairs, in_footprint, of_object),
            "features_by_lod": lods, "surfaces": len(surfaces),
            "inside_footprints": model_distance.summarise(in_d, in_o),
            "whole_tile": model_distance.summarise(all_d, all_o), "picture": picture}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csgtile")
    ap.add_argument("work")
    ap.add_argument("--data", default=DEFAULT_DATA)
    ap.add_argument("--tiles", default="delft,ams")
    ap.add_argument("--runs", default="derived,footprints")
    ap.add_argument("--split", type=float, default=0.0)
    ap.add_argument("--split-points", type=int, default=0)
    ap.add_argument("--cell-size", type=float, default=0.0)
    ap.add_argument("--halo", type=float, default=0.0)
    ap.add_argument("--min-within", action="append", default=[])
    ap.add_argument("--max-rmse", action="append", default=[])
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    report = {"measure": "3D distance of class-6 points to the published model", "runs": {}}
    for tile in args.tiles.split(","):
        spec = TILES[tile]
        run_input = os.path.join(args.data, spec["run_input"])
        las = os.path.join(args.data, spec["las"])
        kind, fp, layer = spec["footprints"]
        fp = os.path.join(args.data, fp)
        if not (os.path.exists(run_input) and os.path.exists(las) and os.path.exists(fp)):
            print(f"skip {tile}: shared data absent", file=sys.stderr)
            continue
        points = read_las(las)
        buildings = read_footprints(kind, fp, layer)
        suffix = ""
        if args.split > 0:
            suffix = f"_split{args.split:g}"
            run_input = os.path.join(args.work, tile + suffix)
            shutil.rmtree(run_input, ignore_errors=True)
            subprocess.run([args.csgtile, "tile", las, "--size", f"{args.split:g}",
                            "--out", run_input], check=True, capture_output=True)
        city = {}
        if args.cell_size > 0:
            city["cell_size"] = f"{args.cell_size:g}"
        if args.halo > 0:
            city["halo"] = f"{args.halo:g}"
        if args.split_points > 0:
            city["split_points"] = args.split_points
            suffix += f"_points{args.split_points}"
        for mode in args.runs.split(","):
            name = f"{tile}_{mode}{suffix}"
            source = city_speed.footprints_source(fp, args.work) if mode == "footprints" else ""
            timing = city_speed.one_run(args.csgtile, args.work, name, run_input, source, layer,
                                        city)
            start = time.monotonic()
            rundir = os.path.join(args.work, name, "runs", name)
            res = measure(points, buildings, model_distance.run_model(rundir),
                          os.path.join(args.work, name + "_distance.png"))
            res["buildings"] = timing["buildings"]
            res["run_wall_s"] = round(timing["wall_s"], 2)
            res["measure_s"] = round(time.monotonic() - start, 1)
            report["runs"][name] = res
    if not report["runs"]:
        print("skip: no tile present", file=sys.stderr)
        sys.exit(77)
    print(json.dumps(report, indent=1, sort_keys=True))
    failures = []
    for spec, key, worse in ((args.min_within, "within_0.3m", lambda v, b: v < b),
                             (args.max_rmse, "rmse_m", lambda v, b: v > b)):
        for item in spec:
            name, bound = item.split("=")
            if name not in report["runs"]:
                continue
            value = report["runs"][name]["inside_footprints"][key]
            if worse(value, float(bound)):
                failures.append(f"{name}: {key} {value:.3f} (bound {bound})")
    if failures:
        sys.exit("city_quality: FAIL: " + "; ".join(failures))


if __name__ == "__main__":
    main()
