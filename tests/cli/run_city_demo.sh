#!/bin/sh
# The README's city run exactly as deploy/run-demo.sh makes it (synth → tile → run
# config/examples/city.yaml), in a temporary working directory: it ends with exit 0, no dead
# job, several cells, every cell with its index, CityJSONSeq, glb and manifest, the run's
# index, root tileset and report.
# Usage: run_city_demo.sh CSGTILE SOURCE_DIR
set -eu
bin=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
mkdir -p out/city
"$bin" synth city-block --out out/city/block.las --truth out/city/truth.json --points 200000 >/dev/null
"$bin" tile out/city/block.las --size 50 --out out/city/tiles >/dev/null
CSGTILE_LOG__LEVEL=warn "$bin" run "$src/config/examples/city.yaml" --json >run.json
run=out/city/runs/city
python3 - "$run" <<'PY'
import json, os, sys
run = sys.argv[1]
m = json.load(open(f"{run}/manifest.json"))
assert m["kind"] == "city" and m["dead"] == [], m["dead"]
assert m["totals"]["tiles"] >= 9 and m["totals"]["cells"] >= 2, m["totals"]
for cell in m["cells"]:
    d = os.path.dirname(f"{run}/{cell['manifest']['key']}")
    for name in ("index.gpkg", "model.city.jsonl", "model.csgt", "manifest.json"):
        assert os.path.exists(f"{d}/{name}"), (d, name)
for name in ("index.gpkg", "tiles/tileset.json", "report/index.html", "timings.json"):
    assert os.path.exists(f"{run}/{name}"), name
print("city demo:", json.dumps(m["totals"]))
PY
