#!/bin/sh
# The README's demo scenes placed in RD New + NAP (the demo itself has no CRS, so it writes no
# tiles) publish 3D Tiles: tileset.json names model.glb, which holds the 15 objects (8 + 6 + 1)
# and which the Khronos glTF validator accepts with no errors.
# Usage: run_demo_tiles.sh CSGTILE SOURCE_DIR VALIDATOR_DIR
#   ($CSGTILE_GLTF_VALIDATOR_DIR overrides VALIDATOR_DIR, the npm package gltf-validator)
# Exit 77 (skipped) when node or the validator is missing, unless
# CSGTILE_REQUIRE_GLTF_VALIDATOR=1.
set -eu
bin=$1
src=$2
validator=${CSGTILE_GLTF_VALIDATOR_DIR:-$3}
if ! command -v node >/dev/null 2>&1 || [ ! -f "$validator/package.json" ]; then
  echo "node or gltf-validator ($validator) not found (set CSGTILE_GLTF_VALIDATOR_DIR, or run deploy/run-tests.sh)"
  [ "${CSGTILE_REQUIRE_GLTF_VALIDATOR:-0}" = 1 ] && exit 1
  exit 77
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
cd "$src"
inputs=""
for scene in pavilion courtyard_block pavilion_fused; do
  sed '1s/^{/{"crs":"EPSG:28992+5709","origin":[155000,463000,1.25],/' \
    "config/examples/scenes/$scene.json" >"$out/$scene.json"
  inputs="$inputs${inputs:+,}$out/$scene.json"
done
CSGTILE_RUN__OUTPUT="$out/run" CSGTILE_RUN__INPUTS="$inputs" CSGTILE_LOG__LEVEL=error \
  "$bin" run config/examples/demo.yaml >/dev/null
run="$out/run/runs/demo"
grep -q '"key": "tiles/tileset.json"' "$run/manifest.json"
grep -q '"objects": 15' "$run/manifest.json"
grep -q '"uri": "model.glb"' "$run/tiles/tileset.json"
report=$(node "$src/tests/support/validate_gltf.cjs" "$validator" "$run/tiles/model.glb")
echo "$report"
echo "$report" | grep -q '"numErrors":0,' || { echo "gltf-validator found errors"; exit 1; }
echo "demo tiles: ok"
