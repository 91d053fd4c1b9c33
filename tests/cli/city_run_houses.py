#!/usr/bin/env python3
"""Adjoining houses split where their roofs say so (issue #18 item 2), end to end, without
footprints: a classified LAS written here — a row of three gabled houses, 7 m wide and 10 m
deep, eaves at 6 m, ridges at 9, 11 and 9.5 m (each house's gable a height step against its
neighbour's), a 2 × 2 m chimney to 10.8 m on the middle one's slope, and an L-shaped hipped house on its own
whose hips and valley are one roof — ground class 2 and buildings class 6 at 10 points per m²
(σ 2 cm), `csgtile run` with default settings, and:
  * four Buildings, each fused and with derived outlines (no footprint_id); the row's volume
    within 3 % of its truth, each row house (told by its extent's centre) within 8 % (the
    step between two houses is placed to a cell of the roof partition's grid, 0.5 m of 7 m);
  * party walls: the GeoPackage's object relations have the row's neighbours touching over
    a wall of at least 25 m² (first and second, second and third), and no other pair;
  * val3dity finds every feature of the CityJSONSeq valid (skipped with a message when the
    validator is absent);
  * with fit.primitives.split_houses false, the row is one Building.
Prints one JSON line of figures. Usage: city_run_houses.py CSGTILE SOURCE_DIR WORK_DIR
"""
import json
import math
import os
import random
import shutil
import sqlite3
import sys

from city_las import city_objects, run_city, seen_from_above, val3dity_valid, write_las

binary, source, work = sys.argv[1:4]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
X0, Y0 = 85000.0, 447500.0
W, D, EAVES = 7.0, 10.0, 6.0
RIDGES = (9.0, 11.0, 9.5)
CHIMNEY = (X0 + 1.5 * W - 1.0, Y0 + 2.5, X0 + 1.5 * W + 1.0, Y0 + 4.5, 10.8)
# The hipped L: wings 8 m wide (x from LX, y from LY), eaves at 5 m, slopes of 0.6.
LX, LY = X0 + 32.0, Y0 - 4.0


def gable(x, y):
    """The row's roof height at (x, y), None outside it."""
    if not (X0 <= x < X0 + 3 * W and Y0 <= y <= Y0 + D):
        return None
    cx0, cy0, cx1, cy1, ctop = CHIMNEY
    if cx0 <= x <= cx1 and cy0 <= y <= cy1:
        return ctop
    ridge = RIDGES[min(2, int((x - X0) // W))]
    return ridge - (ridge - EAVES) * abs(y - (Y0 + D / 2)) / (D / 2)


def hipped(x, y):
    def wing(x0, x1, y0, y1):
        if not (x0 <= x <= x1 and y0 <= y <= y1):
            return None
        return 5.0 + 0.6 * min(x - x0, x1 - x, y - y0, y1 - y)
    heights = [h for h in (wing(LX, LX + 8, LY, LY + 18), wing(LX, LX + 18, LY, LY + 8))
               if h is not None]
    return max(heights) if heights else None


def roof(x, y):
    z = gable(x, y)
    return z if z is not None else hipped(x, y)


points = seen_from_above(random.Random(11), X0 - 15, Y0 - 15, 70, 40, roof)
tile = os.path.join(work, "houses.las")
write_las(tile, points, "csgtile city_run_houses")


def volume_of_house(k):
    """The row house k's true volume (with the chimney on the middle one)."""
    ridge = RIDGES[k]
    v = W * D * EAVES + 0.5 * W * D * (ridge - EAVES)
    if k == 1:
        cx0, cy0, cx1, cy1, ctop = CHIMNEY
        # Under the chimney the roof rises evenly (below the ridge).
        def under(y):
            return ridge - (ridge - EAVES) * abs(y - (Y0 + D / 2)) / (D / 2)
        mean_roof = 0.5 * (under(cy0) + under(cy1))
        v += (cx1 - cx0) * (cy1 - cy0) * (ctop - mean_roof)
    return v


val3dity = os.path.join(source, "..", "shared", "tools", "val3dity", "val3dity")
if not os.path.exists(val3dity):
    print(f"val3dity absent ({val3dity}): validity not checked", file=sys.stderr)
figures = {}
for name, extra in (("split", ""), ("whole", "fit:\n  primitives:\n    split_houses: false\n")):
    rundir, objects = run_city(binary, work, name, tile, extra)
    for o in objects:
        assert o["fused"], (name, o["id"], o["error"])
        assert o.get("footprint_id") is None, (name, o["id"], o.get("footprint_id"))

    features = 0
    seqs, city_objects_ = city_objects(rundir)
    for oid, o in city_objects_:
        if o["type"] == "Building":
            assert o.get("geometry"), (name, oid)
            features += 1
    valid = val3dity_valid(val3dity, seqs, name)
    assert valid in (None, features), (name, valid, features)
    volumes = sorted(round(o["volume"], 1) for o in objects)
    row_truth = [volume_of_house(k) for k in range(3)]
    if name == "whole":
        assert len(objects) == 2, (name, len(objects), volumes)
        figures[name] = {"buildings": len(objects), "volumes": volumes}
        continue
    assert len(objects) == 4, (name, len(objects), volumes)
    assert features == 4, (name, features)
    # Each row house by the centre of its extent along the row, the L the fourth.
    db = sqlite3.connect(f"{rundir}/index.gpkg")
    house_of, row = {}, {}
    for oid, v, x0, x1 in db.execute("SELECT object_id, volume, min_x, max_x FROM objects"):
        k = int((0.5 * (x0 + x1) - X0) // W)
        if 0 <= k < 3:
            assert k not in house_of.values(), (name, "two objects over house", k)
            house_of[oid] = k
            truth = row_truth[k]
            assert abs(v - truth) <= 0.08 * truth, (name, k, v, truth)
            row[k] = v
    assert sorted(house_of.values()) == [0, 1, 2], (name, house_of)
    assert abs(sum(row.values()) - sum(row_truth)) <= 0.03 * sum(row_truth), (name, row)
    walls = {}
    for a, b, s in db.execute("SELECT object_id, other_id, shared_area FROM object_relations "
                              "WHERE relation = 'touches'"):
        if s and s > 1.0:
            pair = tuple(sorted((house_of.get(a, 9), house_of.get(b, 9))))
            walls[pair] = max(walls.get(pair, 0.0), s)
    assert set(walls) == {(0, 1), (1, 2)}, (name, walls)
    assert all(s >= 25.0 for s in walls.values()), (name, walls)
    figures[name] = {"buildings": len(objects), "volumes": volumes,
                     "truth": [round(t, 1) for t in row_truth],
                     "party_walls_m2": {f"{a}-{b}": round(s, 1) for (a, b), s in walls.items()},
                     "features_valid": valid}
print(json.dumps(figures))
