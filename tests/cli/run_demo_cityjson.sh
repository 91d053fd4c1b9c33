#!/bin/sh
# The README's demo run publishes model.city.jsonl (a header line and 15 features: 8 + 6 + 1)
# that the official CityJSON 2.0.2 schemas accept (ajv-cli: header against
# cityjson.min.schema.json, each feature line against cityjsonfeature.min.schema.json).
# Usage: run_demo_cityjson.sh CSGTILE SOURCE_DIR AJV   ($CSGTILE_AJV overrides AJV)
# Exit 77 (skipped) when ajv or the schemas (../shared/schemas) are missing; a missing ajv
# fails instead when CSGTILE_REQUIRE_AJV=1.
set -eu
bin=$1
src=$2
ajv=${CSGTILE_AJV:-$3}
schemas="$src/../shared/schemas/cityjson-2.0.2"
if [ ! -f "$schemas/cityjson.min.schema.json" ]; then
  echo "CityJSON 2.0.2 schemas not found in $schemas"
  exit 77
fi
if [ ! -x "$ajv" ]; then
  echo "ajv not found at $ajv (set CSGTILE_AJV, or run deploy/run-tests.sh)"
  [ "${CSGTILE_REQUIRE_AJV:-0}" = 1 ] && exit 1
  exit 77
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
cd "$src"
CSGTILE_RUN__OUTPUT="$out" CSGTILE_LOG__LEVEL=error "$bin" run config/examples/demo.yaml >/dev/null
model="$out/runs/demo/model.city.jsonl"
grep -q '"key": "model.city.jsonl"' "$out/runs/demo/manifest.json"
lines=$(wc -l <"$model")
[ "$lines" -eq 16 ] || { echo "expected 16 lines, got $lines"; exit 1; }
mkdir "$out/lines"
split -l 1 -d -a 3 --additional-suffix=.json "$model" "$out/lines/line"
header="$out/lines/line000.json"
set --
for f in "$out"/lines/line*.json; do
  [ "$f" = "$header" ] || set -- "$@" -d "$f"
done
check() { "$ajv" validate --spec=draft7 -c ajv-formats --strict=false "$@"; }
check -s "$schemas/cityjson.min.schema.json" -d "$header"
check -s "$schemas/cityjsonfeature.min.schema.json" "$@"
echo "demo cityjson: ok"
