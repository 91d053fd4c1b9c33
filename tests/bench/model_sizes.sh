#!/bin/sh
# Issue #9's size figures: the timber gate and the city block (ground-truth primitives of
# `csgtile synth`, assembled into unified objects by `csgtile assemble`) as native models,
# against the same models as glb and binary STL at 1 mm chordal error. Prints JSON.
# Usage: tests/bench/model_sizes.sh [BUILD_DIR]   (default build)
set -eu
build=${1:-build}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for scene in gate city-block; do
  "$build/csgtile" synth "$scene" --out "$work/$scene.las" --truth "$work/$scene.json" --points 1000 >/dev/null
  "$build/csgtile" assemble "$work/$scene.json" --out "$work/$scene" >/dev/null
  cp "$work/$scene/model.csgt" "$work/$scene.csgt"
done
cd "$work"
"$OLDPWD/$build/tests/bench/model_sizes" --chordal 0.001 gate.csgt city-block.csgt
