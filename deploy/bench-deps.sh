#!/usr/bin/env bash
# Installs the baselines the benchmarks of issue #22 measure csgtile against, in the same run:
# OpenCASCADE 7.6 (tests/bench/occt_fuse_bench) and CGAL 5.5 (tests/bench/cgal_ransac_bench),
# both from Debian. Not needed to build, test or run csgtile; re-run cmake afterwards so that
# the two benches are configured. Usage: deploy/bench-deps.sh (as root, or with sudo)
set -euo pipefail
# libocct-visualization-dev: Debian 12 ships NCollection_AliasedArray.hxx, which every
# header that includes BRep_Builder.hxx needs, in that package.
packages=(libocct-modeling-algorithms-dev libocct-modeling-data-dev libocct-foundation-dev
          libocct-visualization-dev libcgal-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${#missing[@]}" -eq 0 ]; then
  echo "bench-deps: all present"
  exit 0
fi
sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
$sudo apt-get update
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y --no-install-recommends "${missing[@]}"
