#!/usr/bin/env bash
# Quick start, command 1: installs what is missing, builds csgtile, and runs the demo job on
# the embedded default (SQLite queue, local output folder, sample scenes shipped in
# config/examples/scenes), then the city run of LIDAR tiles (config/examples/city.yaml).
set -euo pipefail
cd "$(dirname "$0")/.."
deploy/setup.sh
# The run report's 3D view: three and esbuild from npm, bundled into csgtile when CMake
# configures (without them report/index.html says "3D view unavailable").
deploy/npm-deps.sh viewer
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target csgtile
build/csgtile run config/examples/demo.yaml
# The city run (config/examples/city.yaml): a synthetic airborne scan of the city block, cut
# into 50 m tiles, fitted, assembled per 100 m cell and indexed. Results: out/city/runs/city/
# (manifest.json, cells/<cell>/…, index.gpkg, tiles/tileset.json, report/index.html).
mkdir -p out/city
build/csgtile synth city-block --out out/city/block.las --truth out/city/truth.json --points 200000
build/csgtile tile out/city/block.las --size 50 --out out/city/tiles
build/csgtile run config/examples/city.yaml
