#!/usr/bin/env bash
# Installs every Debian package csgtile needs to build, test and run.
# Idempotent: when everything is present it only checks (a second or two) and exits.
# Usage: deploy/setup.sh                (as root, or with sudo available)
#        deploy/setup.sh --build-only   only what building the csgtile binary needs (the
#                                       container image's build stage, deploy/container/)
set -euo pipefail
build_only=0
[ "${1:-}" = "--build-only" ] && build_only=1

packages=(
  # toolchain
  build-essential cmake ninja-build ccache git pkg-config clang clang-format clang-tidy
  libclang-rt-14-dev
  # kernel
  libeigen3-dev libgmp-dev
  # kernel/assembly: OpenVDB voxel culling and TBB (OpenVDB's headers need Boost's)
  libopenvdb-dev libtbb-dev libboost-dev
  # the csgtile binary's allocator (worker/CMakeLists.txt)
  libjemalloc-dev
  # geo: georeferencing (GeographicLib); PROJ's cs2cs is the tests' independent oracle
  libgeographiclib-dev proj-bin
  # geo: CRS definitions and transformations (PROJ, with its data)
  libproj-dev proj-data
  # geo: building footprints from any vector source (GDAL/OGR); roof partitions clipped to
  # them (Boost.Geometry, headers only)
  libgdal-dev libboost-dev
  # geo fitting: PCL 1.13 (outlier removal, voxel grid, kd-tree neighbourhoods, Euclidean
  # clustering; PCL's templates are instantiated in our code, only libpcl_common and FLANN
  # are linked)
  libpcl-dev
  # config
  libyaml-cpp-dev libvalijson-dev nlohmann-json3-dev
  # worker and command line
  libcli11-dev libsqlite3-dev libssl-dev
  # fetch: libcurl (file://, http(s)://, s3:// with our own SigV4 signing)
  libcurl4-openssl-dev
  # PostgreSQL job queue: libpq; its tests start a real server (and make TLS certificates)
  libpq-dev postgresql-15 openssl
  # tests and benchmarks
  libgtest-dev libgmock-dev googletest libbenchmark-dev python3
  # topology index checks: ogrinfo and GDAL's GeoPackage validator (validate_gpkg.py)
  gdal-bin python3-gdal
  # deploy/k8s checks: YAML lint of the Kubernetes manifests (tests/deploy)
  yamllint
  # val3dity (../shared/tools/val3dity, prebuilt for Debian 12) on published CityJSON: its
  # runtime libraries
  libgeos-c1v5 libgmp10 libmpfr6 libboost-filesystem1.74.0
  # run report check: headless Chromium opens report/index.html (tests/cli/report_chromium.py)
  chromium
)
# Tools, tests and linters that building the binary does not need (left out by --build-only).
test_only=(clang clang-format clang-tidy libclang-rt-14-dev git proj-bin postgresql-15 openssl
           libgeos-c1v5 libmpfr6 libboost-filesystem1.74.0
           libgtest-dev libgmock-dev googletest libbenchmark-dev python3 gdal-bin python3-gdal
           yamllint chromium)
if [ "$build_only" = 1 ]; then
  kept=()
  for p in "${packages[@]}"; do
    [[ " ${test_only[*]} " == *" $p "* ]] || kept+=("$p")
  done
  packages=("${kept[@]}")
fi

# CityJSON schema and glTF checks: ajv-cli and gltf-validator from npm (deploy/run-tests.sh
# installs them into build/npm).
# Node.js and npm come from Debian unless both are on the PATH already: Debian's npm package
# conflicts with other builds of nodejs (e.g. NodeSource's, which bundles npm).
if [ "$build_only" = 0 ] && { ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; }; then
  packages+=(nodejs npm)
fi

# /dev/null must be the null device: initdb (the PostgreSQL tests) writes to it as the
# postgres user. On this machine kind it was once found replaced by a regular root-only file.
if [ ! -c /dev/null ] && [ "$(id -u)" -eq 0 ]; then
  echo "setup: /dev/null is not the null device; restoring it" >&2
  rm -f /dev/null && mknod -m 666 /dev/null c 1 3
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q '^install ok installed$'; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  sudo="sudo"
fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
