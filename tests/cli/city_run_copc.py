#!/usr/bin/env python3
"""A city run over one COPC input (../shared/data/laz/1.2-with-color.copc.laz):
  * the input stands for one fit job per cell of city.cell_size its extent covers
    (tiles.json lists them); each job reads the octree nodes meeting its cell grown by
    city.halo, and its point count equals the reference LAS's points inside that box;
  * `csgtile fit URL` and `csgtile tile URL` give the same bytes as for the local file;
  * `csgtile info URL` shows the header, the VLRs and the octree as for the local file,
    fetching less than the file;
  * the same run with the input given as an http:// URL on a loopback server that honours
    Range requests publishes the same outputs, and no job downloads the file: each fit
    record's range_reads fetched fewer bytes than the file holds, and the server never
    served the whole object.
Skips with a message when the shared data is absent.
Usage: city_run_copc.py CSGTILE SOURCE_DIR WORKDIR"""
import json
import os
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from city_runs import run_city  # noqa: E402
from las_xy import count_in_cells, las_xy  # noqa: E402
import urllib.request

binary, source, work = sys.argv[1:4]
laz_dir = os.path.join(source, "..", "shared", "data", "laz")
copc = os.path.join(laz_dir, "1.2-with-color.copc.laz")
reference = os.path.join(laz_dir, "1.2-with-color.copc.las")
if not os.path.exists(copc) or not os.path.exists(reference):
    print(f"skip: shared data absent ({copc})")
    sys.exit(0)
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
CELL, HALO = 2000.0, 50.0


def reference_points():
    return las_xy(reference)


def run(name, inp):
    path = f"{work}/{name}.yaml"
    with open(path, "w") as f:
        f.write(f"run:\n  name: {name}\n  inputs:\n    - {inp}\n  output: {work}/{name}\n"
                f"city:\n  cell_size: {CELL}\n  halo: {HALO}\nlog:\n  level: warn\n")
    manifest, tiles = run_city(binary, path, f"{work}/{name}/runs/{name}")
    records = {j["result"]["cell"]: j["result"] for j in manifest["jobs"]
               if j["key"].startswith("fit:") and "cell" in j.get("result", {})}
    return manifest, tiles, records


points = reference_points()
manifest, tiles, records = run("local", copc)
assert len(tiles) > 1 and all(isinstance(t, dict) and "cell" in t for t in tiles), tiles
for t in tiles:
    column, row = t["cell"]
    inside = count_in_cells(points, CELL, HALO, (column, row), (column, row))
    name = f"c{column}_r{row}"
    assert name in records, (name, sorted(records))
    assert records[name]["points"] == inside, (name, records[name]["points"], inside)
print(f"local: {len(tiles)} cell jobs; fit records found for {len(records)}")

# The same run over HTTP range requests.
server = subprocess.Popen(["python3", os.path.join(source, "tests", "support", "fault_http_server.py"),
                           laz_dir], stdout=subprocess.PIPE, text=True)
try:
    port = server.stdout.readline().strip()
    base = f"http://127.0.0.1:{port}"
    manifest_http, tiles_http, records_http = run("http", f"{base}/range/1.2-with-color.copc.laz")
    assert len(tiles_http) == len(tiles)
    assert manifest_http["totals"] == manifest["totals"], (manifest_http["totals"], manifest["totals"])
    size = os.path.getsize(copc)
    assert records_http, "no fit record found"
    for name, rec in sorted(records_http.items()):
        assert "range_reads" in rec, rec
        print(f"  {name}: {rec['points']} points, {rec['range_reads']['bytes']} bytes in "
              f"{rec['range_reads']['requests']} requests")
        # A cell holding few of the points fetches less than the file: the first 16 KiB
        # (header, VLRs: half of this small file), the chunk table, the hierarchy and its
        # nodes' chunks (the upper levels meet every cell).
        if rec["points"] < 0.1 * len(points):
            assert rec["range_reads"]["bytes"] < size, (name, rec["range_reads"], size)
        assert rec["points"] == records[name]["points"], name
    fetched = sum(r["range_reads"]["bytes"] for r in records_http.values())
    # This file is small (33 KB): the fixed part (first 16 KiB, chunk table, hierarchy, upper
    # levels) dominates; on a large COPC a cell fetches its share of the nodes.
    assert fetched < len(records_http) * size, (fetched, len(records_http), size)
    # `csgtile info URL`: the header, VLRs and the octree by range requests, as for the file.
    def info(target):
        p = subprocess.run([binary, "info", target, "--json"], capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
        return json.loads(p.stdout)
    remote, local_info = info(f"{base}/range/1.2-with-color.copc.laz"), info(copc)
    assert remote["copc"] == local_info["copc"] and remote["copc"]["nodes"] > 1, remote["copc"]
    assert remote["fetched"]["bytes"] < size, remote["fetched"]
    for key in ("description", "point_count", "bounds", "crs", "vlrs", "evlrs"):
        assert remote[key] == local_info[key], key
    # `csgtile fit URL` and `csgtile tile URL` read by range requests, as they read the file.
    ahn = os.path.join(laz_dir, "ahn3_cropped_2.laz")
    for target, out in ((ahn, "local"), (f"{base}/range/ahn3_cropped_2.laz", "remote")):
        p = subprocess.run([binary, "fit", target, "--out", f"{work}/fit_{out}.json",
                            "--crs", "EPSG:28992"], capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
        p = subprocess.run([binary, "tile", target, "--size", "100", "--out", f"{work}/tiles_{out}"],
                           capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
    assert open(f"{work}/fit_local.json", "rb").read() == open(f"{work}/fit_remote.json", "rb").read()
    names = sorted(os.listdir(f"{work}/tiles_local"))
    assert names and names == sorted(os.listdir(f"{work}/tiles_remote")), names
    for n in names:
        assert open(f"{work}/tiles_local/{n}", "rb").read() == \
            open(f"{work}/tiles_remote/{n}", "rb").read(), n
    counts = json.loads(urllib.request.urlopen(f"{base}/counts").read())
    assert not any(k.startswith("/ok/") for k in counts), counts
    sent = json.loads(urllib.request.urlopen(f"{base}/bytes").read())
    print(f"http: {sum(sent.values())} bytes sent in {sum(counts.values())} requests for "
          f"{len(tiles_http)} cell jobs over a {size}-byte file; per job at most "
          f"{max(r['range_reads']['bytes'] for r in records_http.values())} bytes")
finally:
    server.kill()
print("ok")
