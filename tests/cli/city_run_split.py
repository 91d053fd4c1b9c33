#!/usr/bin/env python3
"""A city run over one LAZ tile of more points than city.split_points (issue #22, memory):
  * the tile stands for one fit job per block of cells (tiles.json lists the blocks; a block
    holds as many cells as hold about split_points points by the header's density);
  * each block's job streams the file and keeps the points inside its block grown by
    city.halo: its point count equals the LAS reference's points inside that box;
  * with the BGT footprints, every footprint that the whole tile's run (split_points 0, the
    same cells) publishes as a building is published once, in one cell, by the blocks' run;
  * the blocks' runs are deterministic: a second run with two threads writes the same cells;
  * a tiles.json entry it cannot read fails the run, naming the entry.
Real data: ../shared/data/laz/ahn3_cropped_2.laz (AHN3 Delft, 208 432 points) with its LAS
reference, footprints ../shared/data/3dfier/bgt_pand.sqlite. Skips with a message when absent.
Usage: city_run_split.py CSGTILE SOURCE_DIR WORKDIR"""
import glob
import json
import os
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from city_runs import run_city  # noqa: E402
from las_xy import count_in_cells, las_xy  # noqa: E402

binary, source, work = sys.argv[1:4]
data = os.path.join(source, "..", "shared", "data")
laz = os.path.join(data, "laz", "ahn3_cropped_2.laz")
reference = os.path.join(data, "laz", "ahn3_cropped_2.las")
footprints = os.path.join(data, "3dfier", "bgt_pand.sqlite")
for path in (laz, reference, footprints):
    if not os.path.exists(path):
        print(f"skip: shared data absent ({path})")
        sys.exit(0)
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
CELL, HALO, SPLIT = 50.0, 40.0, 150000


def reference_points():
    return las_xy(reference)


def run(name, split, threads=1):
    path = f"{work}/{name}.yaml"
    with open(path, "w") as f:
        f.write(f"run:\n  name: {name}\n  inputs:\n    - {laz}\n  output: {work}/{name}\n"
                f"  crs: EPSG:28992+5709\n  threads: {threads}\n"
                f"city:\n  cell_size: {CELL:g}\n  halo: {HALO:g}\n  split_points: {split}\n"
                f"  footprints: {footprints}\n  footprints_layer: buildingpart\n"
                "log:\n  level: warn\n")
    rundir = f"{work}/{name}/runs/{name}"
    manifest, tiles = run_city(binary, path, rundir)
    fits = [j["result"] for j in manifest["jobs"] if j["key"].startswith("fit:")]
    # Footprint id -> the cells publishing a Building of it.
    published = {}
    for seq in sorted(glob.glob(f"{rundir}/cells/*/model.city.jsonl")):
        cell = os.path.basename(os.path.dirname(seq))
        with open(seq) as f:
            for line in f.readlines()[1:]:
                for obj in json.loads(line)["CityObjects"].values():
                    fid = obj.get("attributes", {}).get("footprint_id")
                    if obj["type"] == "Building" and fid is not None:
                        published.setdefault(fid, []).append(cell)
    return rundir, tiles, fits, published


rundir, tiles, fits, published = run("blocks", SPLIT)
assert len(tiles) > 1 and all(isinstance(t, dict) and "block" in t for t in tiles), tiles
points = reference_points()
assert len(points) > SPLIT, len(points)
by_block = {f["block"]: f for f in fits}
assert len(by_block) == len(tiles), (sorted(by_block), tiles)
for t in tiles:
    c0, r0, c1, r1 = t["block"]
    inside = count_in_cells(points, CELL, HALO, (c0, r0), (c1, r1))
    name = f"c{c0}_r{r0}-c{c1}_r{r1}"
    assert name in by_block, (name, sorted(by_block))
    assert by_block[name]["points"] == inside, (name, by_block[name]["points"], inside)
    print(f"block {name}: {inside} points (its cells and halo)")

_, whole_tiles, _, whole = run("whole", 0)
assert len(whole_tiles) == 1 and isinstance(whole_tiles[0], str), whole_tiles
assert whole, "the whole tile's run published no footprint building"
twice = {fid: cells for fid, cells in published.items() if len(cells) > 1}
assert not twice, f"footprints published more than once: {twice}"
missing = sorted(set(whole) - set(published))
assert not missing, f"footprints the blocks' run lost: {missing}"
print(f"footprint buildings: {len(published)} (the whole tile's run: {len(whole)}), each once")

# Deterministic whatever the threads: the same cells, byte for byte.
rundir2, _, _, _ = run("blocks2", SPLIT, threads=2)
for seq in sorted(glob.glob(f"{rundir}/cells/*/model.city.jsonl")):
    other = seq.replace(rundir, rundir2)
    assert open(seq, "rb").read() == open(other, "rb").read(), seq
# A tiles.json it cannot read fails the run naming the entry: a run never goes on without
# some of its tiles.
tiles_json = f"{rundir}/tiles.json"
doc = json.load(open(tiles_json))
doc["tiles"][1] = {"input": doc["tiles"][1]["input"], "block": [1, 2, 0]}
json.dump(doc, open(tiles_json, "w"))
p = subprocess.run([binary, "run", f"{work}/blocks.yaml", "--json"], capture_output=True,
                   text=True)
assert p.returncode != 0, p.stdout
assert "tile entry" in p.stdout + p.stderr, p.stdout + p.stderr
print("ok")
