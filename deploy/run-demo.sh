#!/usr/bin/env bash
# Quick start, command 1: installs what is missing, builds csgtile, and runs the demo job on
# the embedded default (SQLite queue, local output folder, sample scenes shipped in
# config/examples/scenes). Results: out/demo/runs/demo/ (manifest.json, objects/, index.gpkg).
set -euo pipefail
cd "$(dirname "$0")/.."
deploy/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target csgtile
build/csgtile run config/examples/demo.yaml
