#!/usr/bin/env python3
"""Buildings in their footprints end to end (issue #18 item 2): `csgtile run` over the real AHN
tiles with city.footprints — Delft (../shared/data/laz/ahn3_cropped_2.laz) with the BGT
buildings of ../shared/data/3dfier/bgt_pand.sqlite (GDAL's SQLite driver, layer buildingpart,
id identificatiebagpnd), Amsterdam (../shared/data/ams/ahn_2386_9702.las) with
ams/bgt_buildings_demo.csv written out here as GeoJSON in RD New (GDAL cannot read that CSV's
coordinate lists) — and for each run:
  * no dead job; the fit record names the footprints read, the buildings made, those without
    points and the features skipped;
  * every object is published with geometry; each footprint building's footprint_id is one of
    the source's ids, and no id names two objects (one building per footprint);
  * val3dity (../shared/tools/val3dity) finds every solid of every building valid, both LoDs;
  * the objects layer of the run's GeoPackage carries footprint_id and outline, and adjoining
    footprint buildings are separate objects whose contact is a `touches` relation with a
    shared area (their party wall: Delft's row houses);
  * every footprint building is one fused solid (LoD2.2; measured: Delft 27 of 27, Amsterdam
    8 of 8).
The Delft tile is also cut by `csgtile tile` into 50 m tiles (its LAS reference
3dfier/ahn3_cropped_2.las) and run as a directory of tiles: buildings across the tiles' edges
are fitted once, by one tile with its neighbours' points, so the same footprints give the same
buildings as the whole tile, one object each (before: a footprint across two tiles gave an
object per tile).
A run whose footprints name a layer the source lacks stops before any job (exit 78, naming
city.footprints and the layers there are). Prints the counts as JSON. Skips with a message when the shared data is absent; val3dity and
GDAL are required when the data is present.
Usage: city_run_footprints.py CSGTILE SOURCE_DIR WORK_DIR
"""
import csv
import glob
import json
import os
import shutil
import sqlite3
import subprocess
import sys

binary, source, work = sys.argv[1:4]
data = os.path.join(source, "..", "shared", "data")
runs = {
    "delft": (os.path.join(data, "laz", "ahn3_cropped_2.laz"),
              os.path.join(data, "3dfier", "bgt_pand.sqlite"), "buildingpart",
              "identificatiebagpnd"),
    "delft_tiles": (os.path.join(work, "delft_tiles_in"),
                    os.path.join(data, "3dfier", "bgt_pand.sqlite"), "buildingpart",
                    "identificatiebagpnd"),
    "ams": (os.path.join(data, "ams", "ahn_2386_9702.las"),
            os.path.join(data, "ams", "bgt_buildings_demo.csv"), "", "id"),
}
val3dity = os.path.join(source, "..", "shared", "tools", "val3dity", "val3dity")
delft_las = os.path.join(data, "3dfier", "ahn3_cropped_2.las")
missing = [p for k, r in runs.items() for p in r[:2] if k != "delft_tiles" and not os.path.exists(p)]
missing += [] if os.path.exists(delft_las) else [delft_las]
if missing:
    print(f"skip: shared data absent ({', '.join(missing)})")
    sys.exit(0)
if not os.path.exists(val3dity):
    sys.exit(f"val3dity is required beside the shared data: {val3dity} is missing")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
subprocess.run([binary, "tile", delft_las, "--size", "50", "--out", runs["delft_tiles"][0]],
               check=True, capture_output=True)
assert len(os.listdir(runs["delft_tiles"][0])) >= 6, os.listdir(runs["delft_tiles"][0])


def source_ids(path, layer, id_field):
    if path.endswith(".sqlite"):
        db = sqlite3.connect(path)
        return {str(r[0]) for r in db.execute(f"SELECT {id_field} FROM {layer}")}
    return {f["properties"][id_field] for f in json.load(open(path))["features"]}


# A run whose footprints name a layer the source does not have stops before any job, naming
# the key, the line and the layers there are (exit 78, config invalid).
with open(f"{work}/bad.yaml", "w") as f:
    f.write(f"run:\n  name: bad\n  inputs:\n    - {runs['delft'][0]}\n  output: {work}/bad\n"
            f"  crs: EPSG:28992+5709\ncity:\n  footprints: {runs['delft'][1]}\n"
            "  footprints_layer: panden\n")
p = subprocess.run([binary, "run", f"{work}/bad.yaml"], capture_output=True, text=True)
assert p.returncode == 78, (p.returncode, p.stdout, p.stderr)
assert "city.footprints" in p.stderr and "no layer 'panden'" in p.stderr and "buildingpart" in p.stderr, p.stderr
assert not os.path.exists(f"{work}/bad/runs"), "a run started"

summary = {}
for name, (tile, footprints, layer, id_field) in runs.items():
    if footprints.endswith(".csv"):
        features = []
        with open(footprints, newline="") as f:
            for i, row in enumerate(csv.DictReader(f)):
                ring = json.loads(row["polygon"])
                features.append({"type": "Feature", "properties": {"id": f"ams-{i}"},
                                 "geometry": {"type": "Polygon", "coordinates": [ring]}})
        footprints = f"{work}/{name}_footprints.geojson"
        with open(footprints, "w") as f:
            json.dump({"type": "FeatureCollection",
                       "crs": {"type": "name",
                               "properties": {"name": "urn:ogc:def:crs:EPSG::28992"}},
                       "features": features}, f)
    ids = source_ids(footprints, layer, id_field)
    config = f"{work}/{name}.yaml"
    with open(config, "w") as f:
        f.write(f"run:\n  name: {name}\n  inputs:\n    - {tile}\n  output: {work}/{name}\n"
                "  crs: EPSG:28992+5709\n"
                f"city:\n  footprints: {footprints}\n  footprints_layer: \"{layer}\"\n"
                f"  footprints_id: {id_field}\nlog:\n  level: warn\n")
    p = subprocess.run([binary, "run", config, "--json"], capture_output=True, text=True)
    assert p.returncode == 0, f"{name}: exit {p.returncode}\n{p.stdout}\n{p.stderr}"
    rundir = f"{work}/{name}/runs/{name}"
    manifest = json.load(open(f"{rundir}/manifest.json"))
    assert manifest["dead"] == [], (name, manifest["dead"])
    # The fit record (the fit job's result) names what the footprints gave.
    fits = [j["result"] for j in manifest["jobs"] if j["key"].startswith("fit:")]
    assert fits and all("footprints" in r for r in fits), (name, fits)
    read = sum(r["footprints"]["read"] for r in fits)
    made = sum(r["footprints"]["buildings"] for r in fits)
    assert read > 0 and 0 < made <= read, (name, [r["footprints"] for r in fits])
    for r in fits:
        assert isinstance(r["footprints"]["without_building"], list), r["footprints"]
        assert isinstance(r["footprints"]["skipped"], list), r["footprints"]
    problems = []
    for cell in glob.glob(f"{rundir}/cells/*/manifest.json"):
        for problem in json.load(open(cell)).get("problems", []):
            assert "no geometry" not in problem and "left out" not in problem, (name, problem)
            problems.append(problem)
    footprint_ids = []
    unfused = []
    buildings = solids = valid = 0
    for seq in sorted(glob.glob(f"{rundir}/cells/*/model.city.jsonl")):
        with open(seq) as f:
            lines = f.readlines()[1:]
        for line in lines:
            for oid, o in json.loads(line)["CityObjects"].items():
                assert o.get("geometry"), (name, oid, "no geometry")
                a = o.get("attributes", {})
                if a.get("outline") == "footprint":
                    footprint_ids.append(a["footprint_id"])
                    assert a["footprint_id"] in ids, (name, oid, a["footprint_id"])
                    if o["type"] != "Building" or a.get("lod_reached") != "2.2":
                        unfused.append(oid)
                if o["type"] == "Building":
                    buildings += 1
        report = seq + ".val3dity.json"
        v = subprocess.run([val3dity, seq, "--report", report], capture_output=True, text=True)
        assert os.path.exists(report), (name, v.stdout, v.stderr)
        r = json.load(open(report))
        for feature in r["features"]:
            assert feature["validity"], (name, feature.get("id"), feature)
            valid += 1
        solids += sum(p["total"] for p in r["primitives_overview"] if p["type"] == "Solid")
    assert footprint_ids, (name, "no building stands on a footprint")
    assert len(footprint_ids) == len(set(footprint_ids)), (name, "a footprint id names two objects")
    assert not unfused, (name, unfused, problems)
    # The run's GeoPackage: footprint ids and party walls.
    db = sqlite3.connect(f"{rundir}/index.gpkg")
    cols = {r[1] for r in db.execute("PRAGMA table_info(objects)")}
    assert {"footprint_id", "outline"} <= cols, cols
    fp = dict(db.execute("SELECT object_id, footprint_id FROM objects"))
    walls = [(a, b, s) for a, b, s in db.execute(
        "SELECT object_id, other_id, shared_area FROM object_relations WHERE relation = 'touches'")
        if fp.get(a) and fp.get(b) and fp[a] != fp[b] and s and s > 1.0]
    if name.startswith("delft"):
        assert walls, (name, "no party wall between two footprint buildings")
    if name == "delft_tiles":
        # Each tile read its neighbours and left the buildings they make to them; the same
        # footprints made buildings as in the whole tile.
        assert all(r["neighbours"]["read"] > 0 for r in fits), [r["neighbours"] for r in fits]
        assert sum(r["neighbours"]["footprints_left_to_neighbours"] for r in fits) > 0, fits
        assert set(footprint_ids) == summary["delft"]["ids"], (
            sorted(set(footprint_ids) ^ summary["delft"]["ids"]))
    summary[name] = {"footprints_read": read, "footprint_regions": made,
                     "footprint_buildings": len(footprint_ids), "unfused": unfused,
                     "buildings": buildings, "features_valid": valid,
                     "solids_checked": solids,
                     "party_walls": len(walls) // 2,
                     "party_wall_area_m2": round(sum(s for _, _, s in walls) / 2, 1),
                     "ids": set(footprint_ids)}
for v in summary.values():
    del v["ids"]
print(json.dumps(summary))
