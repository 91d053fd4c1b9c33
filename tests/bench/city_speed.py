#!/usr/bin/env python3
"""Time per building of a city run on the shared real tiles (issue #18's "at most 100 ms per
building on one core, fit to publish"; issue #22's "publish <= 0.5 x assemble, run <= 3 x fit").

For each tile present — Delft (laz/ahn3_cropped_2.laz with 3dfier/bgt_pand.sqlite) and
Amsterdam (ams/ahn_2386_9702.las, footprints from ams/bgt_buildings_demo.csv) — it runs
`csgtile run` with `run.threads: 1` (or `--threads N`), with and without the footprints, `--repeat` times, and
prints JSON per run: the buildings published, the process's wall and CPU seconds (best of the
repeats), ms per building (wall / buildings), and per stage the seconds of the jobs
(timings.json: fit, assemble, a cell's block models, measure, relations and publish) with the
ratios publish / assemble, (publish + blocks + measure + relations) / assemble (what the cells
timed as publishing before those had stages of their own; the JSON key keeps its old name) and
wall / fit.

Usage: city_speed.py CSGTILE WORK_DIR [--data DIR] [--repeat 3] [--tiles delft,ams] [--threads 1]
Standard library only. Exit 77 when no tile is present.
"""
import argparse
import csv
import glob
import json
import os
import resource
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_DATA = os.path.normpath(os.path.join(HERE, "..", "..", "..", "shared", "data"))
TILES = {
    "delft": ("laz/ahn3_cropped_2.laz", "3dfier/bgt_pand.sqlite", "buildingpart"),
    "ams": ("ams/ahn_2386_9702.las", "ams/bgt_buildings_demo.csv", ""),
}


def footprints_source(path, work):
    """A GDAL-readable source: the Amsterdam CSV (WKT-less rings as JSON) becomes GeoJSON."""
    if not path.endswith(".csv"):
        return path
    features = []
    with open(path, newline="") as f:
        for i, row in enumerate(csv.DictReader(f)):
            features.append({"type": "Feature", "properties": {"id": f"ams-{i}"},
                             "geometry": {"type": "Polygon",
                                          "coordinates": [json.loads(row["polygon"])]}})
    out = os.path.join(work, os.path.basename(path) + ".geojson")
    with open(out, "w") as f:
        json.dump({"type": "FeatureCollection",
                   "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::28992"}},
                   "features": features}, f)
    return out


def one_run(binary, work, name, tile, footprints, layer, city=None, threads=1):
    """`city`: further city: keys (name -> value) of the run's configuration."""
    config = os.path.join(work, name + ".yaml")
    out = os.path.join(work, name)
    shutil.rmtree(out, ignore_errors=True)
    with open(config, "w") as f:
        f.write(f"run:\n  name: {name}\n  inputs:\n    - {tile}\n  output: {out}\n"
                f"  crs: EPSG:28992+5709\n  threads: {threads}\n")
        if footprints or city:
            f.write("city:\n")
        if footprints:
            f.write(f"  footprints: {footprints}\n  footprints_layer: \"{layer}\"\n")
        for key, value in (city or {}).items():
            f.write(f"  {key}: {value}\n")
        f.write("log:\n  level: warn\n")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.monotonic()
    p = subprocess.run([binary, "run", config, "--json"], capture_output=True, text=True)
    wall = time.monotonic() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        sys.exit(f"{name}: exit {p.returncode}\n{p.stdout}\n{p.stderr}")
    rundir = os.path.join(out, "runs", name)
    buildings = 0
    for seq in glob.glob(os.path.join(rundir, "cells", "*", "model.city.jsonl")):
        with open(seq) as f:
            for line in f.readlines()[1:]:
                buildings += len(json.loads(line)["CityObjects"])
    stages = {}
    for job in json.load(open(os.path.join(rundir, "timings.json")))["jobs"]:
        kind = job["key"].split(":", 1)[0]
        for stage, s in job["stages"].items():
            key = f"{kind}.{stage}"
            stages[key] = stages.get(key, 0.0) + s
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"buildings": buildings, "wall_s": wall, "cpu_s": cpu, "stages_s": stages}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csgtile")
    ap.add_argument("work")
    ap.add_argument("--data", default=DEFAULT_DATA)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--tiles", default="delft,ams")
    ap.add_argument("--threads", type=int, default=1,
                    help="run.threads (default 1: issue #18's time per building on one core)")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    report = {"threads": args.threads, "repeat": args.repeat, "runs": {}}
    for tile in args.tiles.split(","):
        las, fp, layer = TILES[tile]
        las, fp = os.path.join(args.data, las), os.path.join(args.data, fp)
        if not os.path.exists(las):
            print(f"skip {tile}: {las} absent", file=sys.stderr)
            continue
        for with_fp in (False, True):
            name = f"{tile}_{'footprints' if with_fp else 'derived'}"
            source = footprints_source(fp, args.work) if with_fp else ""
            runs = [one_run(args.csgtile, args.work, name, las, source, layer,
                            threads=args.threads) for _ in range(args.repeat)]
            best = min(runs, key=lambda r: r["wall_s"])
            st = best["stages_s"]
            assemble = st.get("assemble.assemble", 0.0)
            publish = st.get("assemble.publish", 0.0)
            # Before the cells timed their block models (LoD1.2/1.3), the model-to-points
            # measure and the objects' relations (party walls) as stages of their own, all
            # counted as publishing.
            published_all = (publish + st.get("assemble.blocks", 0.0) +
                             st.get("assemble.measure", 0.0) +
                             st.get("assemble.relations", 0.0))
            fit = st.get("fit.fit", 0.0)
            n = max(best["buildings"], 1)
            best.update({
                "ms_per_building_wall": 1000.0 * best["wall_s"] / n,
                "ms_per_building_cpu": 1000.0 * best["cpu_s"] / n,
                "publish_over_assemble": publish / assemble if assemble > 0 else None,
                "publish_blocks_measure_over_assemble":
                    published_all / assemble if assemble > 0 else None,
                "wall_over_fit": best["wall_s"] / fit if fit > 0 else None,
                "wall_s_all_repeats": [r["wall_s"] for r in runs],
            })
            report["runs"][name] = best
    if not report["runs"]:
        print("skip: no tile present", file=sys.stderr)
        sys.exit(77)
    print(json.dumps(report, indent=1, sort_keys=True))


if __name__ == "__main__":
    main()
