#!/usr/bin/env python3
"""A city run end to end: `csgtile synth` scans the city block, `csgtile tile` cuts the scan
into 50 m tiles, and `csgtile run` fits every tile, assembles every 100 m cell (with a 45 m
halo) and indexes the run. One extra input is a truncated tile. Checked:
  * the truncated tile's fit job is dead with a reason naming the file; every other job done;
    the run exits 3 (jobs_failed) and still publishes everything else;
  * every cell's manifest names its files with matching SHA-256 and sizes; every object is
    published in exactly one cell, and the cells' objects are those of the same tiles
    assembled as one cell (none lost, none cut); the run index holds them all;
  * validators on every cell: ogrinfo + GDAL's validate_gpkg.py on each GeoPackage, ajv with
    the CityJSON 2.0.2 schemas on each CityJSONSeq, the Khronos glTF validator on each glb;
    the root tileset names every cell's tileset;
  * the run report names its files with their hashes and renders in headless Chromium;
  * `csgtile query` answers from the run index;
  * the 1-thread run also publishes to S3 (@20minutes/s3rver): the pointer names a manifest
    whose every file is stored with its hash;
  * byte-identical outputs for 1, 2 and 8 threads, and — when PostgreSQL 15 is installed — for
    the same run on PostgreSQL worked by three `csgtile worker` processes at once, one of them
    killed (SIGKILL) and restarted every second or so, six times.
Validators and PostgreSQL are skipped with a message when missing, unless CSGTILE_REQUIRE_GDAL,
CSGTILE_REQUIRE_AJV, CSGTILE_REQUIRE_GLTF_VALIDATOR, CSGTILE_REQUIRE_POSTGRES,
CSGTILE_REQUIRE_S3RVER or CSGTILE_REQUIRE_REPORT_VIEWER is 1.
Prints one JSON line of figures.
Usage: city_run.py CSGTILE SOURCE_DIR WORKDIR AJV GLTF_VALIDATOR_DIR"""
import glob
import hashlib
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time

binary, source, work, ajv, gltf_dir = sys.argv[1:6]
# The validators' locations as the other tests take them (deploy/run-tests.sh exports them;
# a sanitizer build directory has no npm folder of its own).
ajv = os.environ.get("CSGTILE_AJV", ajv)
gltf_dir = os.environ.get("CSGTILE_GLTF_VALIDATOR_DIR", gltf_dir)
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def required(name):
    return os.environ.get(f"CSGTILE_REQUIRE_{name}") == "1"


def missing(name, what):
    if required(name):
        sys.exit(f"{what} is required (CSGTILE_REQUIRE_{name}=1) but missing")
    print(f"skip: {what} missing")


def run(*args, ok=(0,), **kw):
    p = subprocess.run([binary, *args], capture_output=True, text=True, **kw)
    assert p.returncode in ok, f"{args}: exit {p.returncode}\n{p.stdout}\n{p.stderr}"
    return p


# --- inputs: a scanned city block cut into tiles, plus a truncated tile -----------------------
run("synth", "city-block", "--out", f"{work}/block.las", "--truth", f"{work}/truth.json",
    "--points", "200000", "--seed", "3")
tiled = json.loads(run("tile", f"{work}/block.las", "--size", "50", "--out", f"{work}/tiles",
                       "--json").stdout)
tiles = [t["file"] for t in tiled["tiles"]]
assert len(tiles) >= 9, tiled
assert sum(t["points"] for t in tiled["tiles"]) == tiled["points"]
with open(tiles[len(tiles) // 2], "rb") as f:
    whole = f.read()
corrupt = f"{work}/tiles/zz_truncated.las"
with open(corrupt, "wb") as f:
    f.write(whole[: len(whole) // 2])
inputs = tiles + [corrupt]


def write_config(name, output, threads, queue="", cell_size=100, halo=45):
    path = f"{work}/{name}.yaml"
    with open(path, "w") as f:
        f.write("run:\n  name: city\n  inputs:\n" + "".join(f"    - {p}\n" for p in inputs) +
                f"  output: {output}\n  threads: {threads}\ncity:\n  cell_size: {cell_size}\n"
                f"  halo: {halo}\nlog:\n  level: warn\n  format: json\n{queue}")
    return path


# --- the embedded run ------------------------------------------------------------------------
p = run("run", write_config("a", f"{work}/a", 2), "--json", ok=(3,))
summary = json.loads(p.stdout.strip().splitlines()[-1])
rundir = f"{work}/a/runs/city"
manifest = json.load(open(f"{rundir}/manifest.json"))
assert manifest["kind"] == "city"
dead = manifest["dead"]
assert [d["key"] for d in dead] == [f"fit:city:{corrupt}"], dead
assert "input_invalid" in dead[0]["error"] and "zz_truncated.las" in dead[0]["error"], dead
assert dead[0]["attempts"] == 1, dead  # a corrupt tile is not retried
kinds = {}
for job in manifest["jobs"]:
    kinds[job["key"].split(":")[0]] = kinds.get(job["key"].split(":")[0], 0) + 1
assert kinds["fit"] == len(tiles), kinds
totals = manifest["totals"]
assert totals["cells"] >= 2 and kinds["assemble"] == totals["cells"], (totals, kinds)
assert totals["objects"] >= 5 and totals["primitives"] >= totals["objects"], totals


def sha256(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


status = json.loads(run("status", f"{work}/a.yaml", "--json").stdout)["city"]
assert status == {"tiles": len(inputs), "fits_done": len(tiles), "fits_dead": 1,
                  "cells": totals["cells"], "cells_done": totals["cells"], "cells_dead": 0,
                  "indexed": True, "index_dead": False}, status

objects_seen = {}
cells = []
for cell in manifest["cells"]:
    key = cell["manifest"]["key"]
    assert sha256(f"{rundir}/{key}") == cell["manifest"]["sha256"], key
    cm = json.load(open(f"{rundir}/{key}"))
    cdir = os.path.dirname(f"{rundir}/{key}")
    for entry in cm["files"]:
        path = f"{cdir}/{entry['key']}"
        assert sha256(path) == entry["sha256"] and os.path.getsize(path) == entry["bytes"], entry
    for o in cm["objects"]:
        assert o["id"] not in objects_seen, f"{o['id']} in {objects_seen.get(o['id'])} and {cm['cell']}"
        objects_seen[o["id"]] = cm["cell"]
        assert sha256(f"{rundir}/{o['key']}") == o["sha256"], o
    cells.append((cm["cell"], cdir, cm))
assert len(objects_seen) == totals["objects"], (len(objects_seen), totals)


def object_groups(rundir_, manifest_):
    groups = set()
    for cell in manifest_["cells"]:
        cm = json.load(open(f"{rundir_}/{cell['manifest']['key']}"))
        for o in cm["objects"]:
            groups.add(frozenset(p["label"] for p in o["primitives"]))
    return groups


# None lost, none cut: the same tiles as one 5 km cell give the same objects (each object's
# primitives, by label) as the 100 m cells. The halo stays: it also shapes the fits (the band of
# the neighbouring tiles' points each tile's fit reads).
run("run", write_config("whole", f"{work}/whole", 2, cell_size=5000, halo=45), ok=(3,))
whole_dir = f"{work}/whole/runs/city"
whole = json.load(open(f"{whole_dir}/manifest.json"))
assert whole["totals"]["cells"] == 1, whole["totals"]
assert object_groups(rundir, manifest) == object_groups(whole_dir, whole), "objects differ by cell size"

figures = {"tiles": len(tiles), "cells": len(cells), "objects": totals["objects"],
           "primitives": totals["primitives"], "validated": []}

# The run report: every deterministic file named with its hash; the timings beside them.
report = manifest["report"]
assert report["key"] == "report/index.html" and report["not_deterministic"] == ["report/timings.js"]
assert [f["key"] for f in report["files"]][0] == "report/index.html", report
for entry in report["files"]:
    assert sha256(f"{rundir}/{entry['key']}") == entry["sha256"], entry
html = open(f"{rundir}/report/index.html").read()
for name, _, cm in cells:
    assert name in html, name
assert os.path.exists(f"{rundir}/report/timings.js")
chromium = os.environ.get("CSGTILE_CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
puppeteer = os.path.abspath(os.environ.get("CSGTILE_PUPPETEER_DIR", f"{os.path.dirname(gltf_dir)}/puppeteer-core"))
if (shutil.which("node") and os.access(chromium, os.X_OK) and os.path.exists(f"{puppeteer}/package.json")
        and os.path.exists(f"{rundir}/report/viewer.js")):
    seen = subprocess.run(["node", f"{source}/tests/cli/report_chromium.cjs", puppeteer, chromium,
                           f"{rundir}/report/index.html", f"{work}/report.png"],
                          capture_output=True, text=True, timeout=300)
    assert seen.returncode == 0, (seen.stdout, seen.stderr[-2000:])
    figures["validated"].append("report in chromium")
else:
    missing("REPORT_VIEWER", "node, chromium, puppeteer-core or the compiled-in 3D viewer")

# --- validators ------------------------------------------------------------------------------
validate_gpkg = "/usr/lib/python3/dist-packages/osgeo_utils/samples/validate_gpkg.py"
if shutil.which("ogrinfo") and os.path.exists(validate_gpkg):
    for path, count in [(f"{rundir}/index.gpkg", totals["objects"])] + [
            (f"{cdir}/index.gpkg", len(cm["objects"])) for _, cdir, cm in cells]:
        info = subprocess.run(["ogrinfo", "-ro", "-so", path, "objects"], capture_output=True,
                              text=True, check=True).stdout
        assert f"Feature Count: {count}\n" in info, (path, info)
        assert "EPSG" in info and "28992" in info, info
        subprocess.run(["/usr/bin/python3", validate_gpkg, path], check=True)
    figures["validated"].append("gpkg")
else:
    missing("GDAL", "ogrinfo or validate_gpkg.py (gdal-bin, python3-gdal)")

schemas = f"{source}/../shared/schemas/cityjson-2.0.2"
if os.access(ajv, os.X_OK) and os.path.exists(f"{schemas}/cityjson.min.schema.json"):
    for name, cdir, cm in cells:
        lines = open(f"{cdir}/model.city.jsonl").read().splitlines()
        assert len(lines) == 1 + len(cm["objects"]), (name, len(lines))
        parts = f"{work}/cityjson-{name}"
        os.makedirs(parts)
        for i, line in enumerate(lines):
            with open(f"{parts}/{i:04d}.json", "w") as f:
                f.write(line)
        check = [ajv, "validate", "--spec=draft7", "-c", "ajv-formats", "--strict=false"]
        subprocess.run(check + ["-s", f"{schemas}/cityjson.min.schema.json", "-d",
                                f"{parts}/0000.json"], check=True, capture_output=True)
        features = sorted(glob.glob(f"{parts}/0*.json"))[1:]
        if features:
            args = [a for fpath in features for a in ("-d", fpath)]
            subprocess.run(check + ["-s", f"{schemas}/cityjsonfeature.min.schema.json"] + args,
                           check=True, capture_output=True)
    figures["validated"].append("cityjson")
else:
    missing("AJV", "ajv or the CityJSON 2.0.2 schemas")

root = json.load(open(f"{rundir}/tiles/tileset.json"))
children = root["root"]["children"]
assert len(children) == sum(1 for _, _, cm in cells if cm["tiles"]), children
for child in children:
    path = os.path.normpath(f"{rundir}/tiles/{child['content']['uri']}")
    assert os.path.exists(path), path
if shutil.which("node") and os.path.exists(f"{gltf_dir}/package.json"):
    for name, cdir, cm in cells:
        glb = f"{cdir}/tiles/model.glb"
        if not os.path.exists(glb):
            continue
        report = subprocess.run(["node", f"{source}/tests/support/validate_gltf.cjs", gltf_dir, glb],
                                capture_output=True, text=True, check=True).stdout
        assert '"numErrors":0,' in report, (name, report)
    figures["validated"].append("gltf")
else:
    missing("GLTF_VALIDATOR", "node or gltf-validator")

some = sorted(objects_seen)[0]
q = run("query", f"{rundir}/index.gpkg", "--ancestors", f"{some}/vertex/0", "--kind", "edge", "--json")
assert f'"key":"{some}/edge/' in q.stdout, q.stdout


# --- determinism -----------------------------------------------------------------------------
def outputs(output):
    base = f"{output}/runs/city"
    files = {}
    for path in glob.glob(f"{base}/**", recursive=True):
        rel = os.path.relpath(path, base)
        if os.path.isfile(path) and rel not in ("timings.json", "report/timings.js"):
            files[rel] = sha256(path)
    return files


reference = outputs(f"{work}/a")
# The second run (1 thread) also publishes to S3 (s3rver on loopback) when it is installed:
# a reader following the pointer finds every file of the run with its hash.
s3rver = os.path.abspath(os.environ.get("CSGTILE_S3RVER_DIR", f"{os.path.dirname(gltf_dir)}/@20minutes/s3rver"))
s3 = None
extra, env = "", dict(os.environ)
if shutil.which("node") and os.path.exists(f"{s3rver}/package.json"):
    os.makedirs(f"{work}/s3")
    s3 = subprocess.Popen(["node", f"{source}/tests/support/s3_server.cjs", s3rver, f"{work}/s3",
                           "runs"], stdout=subprocess.PIPE, text=True)
    port = int(s3.stdout.readline())
    extra = f"publish:\n  url: s3://runs/city-test\nfetch:\n  s3_endpoint: http://127.0.0.1:{port}\n"
    env.update(AWS_ACCESS_KEY_ID="S3RVER", AWS_SECRET_ACCESS_KEY="S3RVER")
else:
    missing("S3RVER", "@20minutes/s3rver")
try:
    run("run", write_config("b", f"{work}/b", 1, extra), ok=(3,), env=env)
finally:
    if s3:
        s3.terminate()
        s3.wait()
other = outputs(f"{work}/b")
assert other == reference, sorted(set(other.items()) ^ set(reference.items()))[:6]
# And with more threads than cores (every stage's thread count: fit regions, fuse groups, the
# objects of a cell's exports, relations): the same bytes.
run("run", write_config("t8", f"{work}/t8", 8), ok=(3,))
eight = outputs(f"{work}/t8")
assert eight == reference, sorted(set(eight.items()) ^ set(reference.items()))[:6]
figures["identical"] = ["threads 1 vs 2", "threads 8 vs 2"]
if s3:
    stored = f"{work}/s3/runs/city-test"

    def s3_object(key):
        with open(f"{stored}/{key}._S3rver_object", "rb") as f:
            return f.read()

    pointer = json.loads(s3_object("runs/city/CURRENT"))
    published = s3_object(pointer["manifest"])
    assert hashlib.sha256(published).hexdigest() == pointer["sha256"], pointer
    listed = json.loads(published)["files"]
    local = outputs(f"{work}/b")
    for rel, digest in local.items():
        assert rel in listed and listed[rel]["sha256"] == digest, rel
        assert hashlib.sha256(s3_object(listed[rel]["key"])).hexdigest() == digest, rel
    figures["s3_published_files"] = len(listed)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from private_postgres import PrivatePostgres, available as postgres_available  # noqa: E402

if postgres_available():
    server = PrivatePostgres(f"{work}/pg")
    try:
        queue = "queue:\n" + server.queue_yaml()
        # Short leases, and a worker killed (SIGKILL) every 0.7-1.5 s while the run lasts, then
        # restarted as a supervisor would: jobs of killed workers are taken over.
        queue += "  lease_seconds: 2\n  max_attempts: 20\n"
        config = write_config("c", f"{work}/c", 1, queue)
        run("enqueue", config)
        rng = random.Random(5)
        logs = []

        def spawn():
            log = open(f"{work}/worker-{len(logs)}.log", "w")
            logs.append(log)
            return subprocess.Popen([binary, "worker", config, "--exit-when-idle"],
                                    stdout=subprocess.DEVNULL, stderr=log)

        workers = [spawn() for _ in range(3)]
        kills = 0
        deadline = time.time() + 600
        while any(w.poll() is None for w in workers):
            assert time.time() < deadline, "the workers did not finish the city run"
            time.sleep(rng.uniform(0.7, 1.5))
            alive = [i for i, w in enumerate(workers) if w.poll() is None]
            if alive and kills < 6:
                i = rng.choice(alive)
                workers[i].send_signal(signal.SIGKILL)
                workers[i].wait()
                kills += 1
                workers[i] = spawn()
        codes = [w.returncode for w in workers]
        assert all(c in (0, 3) for c in codes), codes
        # Files a killed writer left half-written are dot-prefixed temporaries that no
        # manifest names (publishing skips them); the outputs are the rest.
        pg_outputs = {k: v for k, v in outputs(f"{work}/c").items()
                      if not any(part.startswith(".") for part in k.split("/"))}
        assert pg_outputs == reference, sorted(set(pg_outputs.items()) ^ set(reference.items()))[:6]
        figures["identical"].append(f"postgres, 3 workers, {kills} SIGKILLs")
    finally:
        server.stop()
else:
    missing("POSTGRES", "PostgreSQL 15")

print(json.dumps(figures))
