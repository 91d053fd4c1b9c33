#!/usr/bin/env python3
"""A dome on a drum seen from the air, end to end (issue #18: "a dome on a drum"): a classified
LAS written here (ground class 2 at 10 points per m² over 60 × 60 m, a hemisphere of radius
6 m on a drum 8 m high, class 6, σ 2 cm, the drum's wall at 1 point per m²), `csgtile run`
with default settings, and:
  * one Building, fused from a sphere (cut at its equator) and a cylinder, its volume within
    1 % of the truth (π r² h + 2/3 π r³);
  * its published model RMSE (model_rmse: each point's 3D distance to the LoD2.2 model) below
    5 cm;
  * val3dity finds every feature of the CityJSONSeq valid (skipped with a message when the
    validator is absent).
The same with a footprint (a 48-gon around the drum, GeoJSON read by GDAL): one Building
carrying the footprint's id, the dome standing on the footprint's prism, volume within 1 %,
valid. And a dome over part of a larger roof (a second LAS: a flat roof of 30 x 20 m, 10 m
high, carrying a dome of radius 4 m, walls at 1 point per m², in its rectangular footprint):
one Building of the dome standing on its roof parts, volume within 1 %, RMSE below 5 cm,
valid.
Prints one JSON line of figures. Usage: city_run_dome.py CSGTILE SOURCE_DIR WORK_DIR
"""
import json
import math
import os
import random
import shutil
import sys

from city_las import city_objects, run_city, seen_from_above, val3dity_valid, write_las

binary, source, work = sys.argv[1:4]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
R, H, CX, CY = 6.0, 8.0, 85030.0, 447530.0


rnd = random.Random(7)


def write_footprint(path, fid, ring):
    """One polygon feature (its `id` attribute fid) in RD New, as GeoJSON."""
    with open(path, "w") as f:
        json.dump({"type": "FeatureCollection",
                   "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::28992"}},
                   "features": [{"type": "Feature", "properties": {"id": fid},
                                 "geometry": {"type": "Polygon", "coordinates": [ring]}}]}, f)


def dome_roof(x, y):
    r = math.hypot(x - CX, y - CY)
    return H + math.sqrt(R * R - r * r) if r < R else None


points = seen_from_above(rnd, CX - 30, CY - 30, 60, 60, dome_roof)
for _ in range(int(2 * math.pi * R * H)):
    a, z, rr = rnd.random() * 2 * math.pi, rnd.random() * H, R + rnd.gauss(0, 0.02)
    points.append((CX + rr * math.cos(a), CY + rr * math.sin(a), z, 6))
tile = os.path.join(work, "dome.las")
write_las(tile, points, "csgtile city_run_dome")

footprint = os.path.join(work, "footprint.geojson")
ring = [[CX + R * math.cos(2 * math.pi * k / 48), CY + R * math.sin(2 * math.pi * k / 48)]
        for k in range(48)]
write_footprint(footprint, "dome-1", ring + ring[:1])
# A flat roof (30 x 20 m, 10 m high) carrying a dome of radius 4 m on part of it, its walls at
# 1 point per m², in a rectangular footprint.
RW, RD, RH, RR = 30.0, 20.0, 10.0, 4.0


def domed_flat_roof(x, y):
    if abs(x - CX) >= RW / 2 or abs(y - CY) >= RD / 2:
        return None
    r = math.hypot(x - CX, y - CY)
    return RH + (math.sqrt(RR * RR - r * r) if r < RR else 0.0)


roof_points = seen_from_above(rnd, CX - 30, CY - 30, 60, 60, domed_flat_roof)
for _ in range(int(2 * (RW + RD) * RH)):
    t, z = rnd.random() * 2 * (RW + RD), rnd.random() * RH
    if t < RW:
        x, y = CX - RW / 2 + t, CY - RD / 2
    elif t < RW + RD:
        x, y = CX + RW / 2, CY - RD / 2 + (t - RW)
    elif t < 2 * RW + RD:
        x, y = CX + RW / 2 - (t - RW - RD), CY + RD / 2
    else:
        x, y = CX - RW / 2, CY + RD / 2 - (t - 2 * RW - RD)
    roof_points.append((x, y, z, 6))
roof_tile = os.path.join(work, "domed_roof.las")
write_las(roof_tile, roof_points, "csgtile city_run_dome")
roof_footprint = os.path.join(work, "roof_footprint.geojson")
box = [[CX - RW / 2, CY - RD / 2], [CX + RW / 2, CY - RD / 2], [CX + RW / 2, CY + RD / 2],
       [CX - RW / 2, CY + RD / 2], [CX - RW / 2, CY - RD / 2]]
write_footprint(roof_footprint, "roof-1", box)

val3dity = os.path.join(source, "..", "shared", "tools", "val3dity", "val3dity")
if not os.path.exists(val3dity):
    print(f"val3dity absent ({val3dity}): validity not checked", file=sys.stderr)
figures = {}
footprint_truth = 0.5 * 48 * R * R * math.sin(2 * math.pi / 48) * H + 2.0 / 3.0 * math.pi * R ** 3
cases = (
    ("derived", tile, "", "cylinder", "", math.pi * R * R * H + 2.0 / 3.0 * math.pi * R ** 3),
    ("footprint", tile, f"city:\n  footprints: {footprint}\n  footprints_id: id\n", "extrusion",
     "dome-1", footprint_truth),
    ("roof", roof_tile, f"city:\n  footprints: {roof_footprint}\n  footprints_id: id\n",
     "extrusion", "roof-1", RW * RD * RH + 2.0 / 3.0 * math.pi * RR ** 3))
for name, tile, extra, under, footprint_id, truth in cases:
    rundir, objects = run_city(binary, work, name, tile, extra)
    assert len(objects) == 1, (name, [(o["id"], [q["type"] for q in o["primitives"]])
                                      for o in objects])
    dome = objects[0]
    types = sorted(q["type"] for q in dome["primitives"])
    # The dome and what it stands on: its drum, or the footprint's prism or roof parts.
    assert "sphere" in types and set(types) == set(under.split() + ["sphere"]), (name, types)
    assert dome["fused"], (name, dome["error"])
    if footprint_id:
        assert dome["footprint_id"] == footprint_id, dome["footprint_id"]
    assert abs(dome["volume"] - truth) <= 0.01 * truth, (name, dome["volume"], truth)
    rmse = dome["model_fit"]["rmse"]
    assert rmse < 0.05, (name, dome["model_fit"])
    features = 0
    seqs, city_objects_ = city_objects(rundir)
    for oid, o in city_objects_:
        assert o["type"] == "Building" and o.get("geometry"), (name, oid, o["type"])
        features += 1
    assert features == 1, (name, features)
    valid = val3dity_valid(val3dity, seqs, name)
    assert valid in (None, features), (name, valid, features)
    figures[name] = {"volume": round(dome["volume"], 2), "truth": round(truth, 2),
                     "model_rmse": round(rmse, 4), "features_valid": valid}
print(json.dumps(figures))
