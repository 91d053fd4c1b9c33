#!/bin/sh
# The README's demo run publishes a topology index that GDAL reads (15 objects: 8 + 6 + 1) and
# that GDAL's GeoPackage validator accepts; `csgtile query` answers from it.
# Usage: run_demo_index.sh CSGTILE SOURCE_DIR
# Exit 77 (skipped) when GDAL's tools are missing, unless CSGTILE_REQUIRE_GDAL=1.
set -eu
bin=$1
src=$2
validator=/usr/lib/python3/dist-packages/osgeo_utils/samples/validate_gpkg.py
if ! command -v ogrinfo >/dev/null 2>&1 || [ ! -f "$validator" ]; then
  echo "ogrinfo (gdal-bin) or validate_gpkg.py (python3-gdal) not installed; run deploy/setup.sh"
  [ "${CSGTILE_REQUIRE_GDAL:-0}" = 1 ] && exit 1
  exit 77
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
cd "$src"
CSGTILE_RUN__OUTPUT="$out" CSGTILE_LOG__LEVEL=error "$bin" run config/examples/demo.yaml >/dev/null
index="$out/runs/demo/index.gpkg"
grep -q '"key": "index.gpkg"' "$out/runs/demo/manifest.json"
info=$(ogrinfo -ro -so "$index" objects)
echo "$info" | grep -q "Feature Count: 15" || { echo "$info"; exit 1; }
echo "$info" | grep -q "Geometry: 3D Multi Polygon" || { echo "$info"; exit 1; }
/usr/bin/python3 "$validator" "$index"
# The first column stands on the slab (object 0-4).
"$bin" query "$index" --relations 0-0 | grep -q "^0-4	touches	"
"$bin" query "$index" --ancestors 0-4/vertex/0 --kind edge --json | grep -q '"key":"0-4/edge/'
echo "demo index: ok"
