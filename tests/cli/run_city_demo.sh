#!/bin/sh
# The README's city run exactly as deploy/run-demo.sh makes it (synth → tile → run
# config/examples/city.yaml), in a temporary working directory: it ends with exit 0, no dead
# job, several cells, every cell with its index, CityJSONSeq, glb and manifest, the run's
# index, root tileset and report; and that report opened in headless Chromium
# (report_chromium.cjs: the 3D view ready, not blank, orbiting changes it, no console error, no
# request leaving file://) — issue #20's "the quick start's report has its 3D view".
# The Chromium check needs node, chromium and puppeteer-core ($CSGTILE_PUPPETEER_DIR,
# deploy/npm-deps.sh all) and csgtile built with its viewer (deploy/npm-deps.sh viewer before
# CMake configures, as deploy/run-demo.sh does); without them it is left out with a message,
# unless CSGTILE_REQUIRE_REPORT_VIEWER=1 (deploy/run-tests.sh), which makes each missing part
# a failure.
# Usage: run_city_demo.sh CSGTILE SOURCE_DIR [PUPPETEER_CORE_DIR]
set -eu
bin=$1
src=$2
puppeteer=${CSGTILE_PUPPETEER_DIR:-${3:-}}
chromium=${CSGTILE_CHROMIUM:-$(command -v chromium || echo /usr/bin/chromium)}
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
page=$run/report/index.html
missing=""
if grep -q 'data-viewer="unavailable"' "$page"; then
  missing="csgtile was built without its 3D viewer (deploy/npm-deps.sh viewer, then configure)"
elif ! command -v node >/dev/null 2>&1; then
  missing="node not found"
elif [ ! -x "$chromium" ]; then
  missing="chromium not found ($chromium)"
elif [ -z "$puppeteer" ] || [ ! -f "$puppeteer/package.json" ]; then
  missing="puppeteer-core not found (set CSGTILE_PUPPETEER_DIR)"
fi
if [ -n "$missing" ]; then
  echo "city demo report in Chromium: left out: $missing"
  if [ "${CSGTILE_REQUIRE_REPORT_VIEWER:-0}" = 1 ]; then
    echo "CSGTILE_REQUIRE_REPORT_VIEWER=1: failing instead"
    exit 1
  fi
  exit 0
fi
node "$src/tests/cli/report_chromium.cjs" "$puppeteer" "$chromium" "$work/$page" "$work/report.png"
echo "city demo report: 3D view rendered offline in Chromium"
