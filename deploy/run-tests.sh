#!/usr/bin/env bash
# Quick start, command 2 (and what CI runs): installs what is missing, then
#   1. an optimised build with warnings as errors, and every test (ctest);
#   2. clang-tidy (.clang-tidy, warnings as errors) on every source of kernel/, geo/, config/
#      and worker/ (clang-format is checked by a test of step 1, label boundaries);
#   3. an ASan+UBSan build, and the kernel, assembly, geo, config and CLI tests under it;
#   4. a libFuzzer build (clang) and a short bounded run of each fuzz target.
# Set CSGTILE_SKIP_TIDY=1, CSGTILE_SKIP_SANITIZE=1 or CSGTILE_SKIP_FUZZ=1 to leave out step 2, 3
# or 4 locally.
set -euo pipefail
cd "$(dirname "$0")/.."
# setup.sh installs GDAL: its validators must then run, not skip.
export CSGTILE_REQUIRE_GDAL="${CSGTILE_REQUIRE_GDAL:-1}"
# ... and PostgreSQL 15: the PostgreSQL queue's tests must then run against it, not skip.
export CSGTILE_REQUIRE_POSTGRES="${CSGTILE_REQUIRE_POSTGRES:-1}"
deploy/setup.sh
# OpenCASCADE 7.6 and CGAL 5.5 (Debian): the baselines of tests/bench and the Booleans'
# independent check against OpenCASCADE (ctest bench.occt_volumes_agree).
deploy/bench-deps.sh
jobs="$(nproc)"

echo "== optimised build and full test suite"
# The npm packages (deploy/npm-deps.sh): the run report's 3D view (three and esbuild, bundled
# when CMake configures, so npm runs before it) and the tests' validators and servers (ajv-cli,
# the Khronos glTF validator, s3rver, puppeteer-core for Debian's chromium). The checks must
# then run, not skip.
deploy/npm-deps.sh all
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DCSGTILE_WERROR=ON \
      -DCSGTILE_BUILD_TESTS=ON -DCSGTILE_BUILD_BENCH=ON >/dev/null
cmake --build build -j"$jobs"
export CSGTILE_AJV="$PWD/build/npm/node_modules/.bin/ajv"
export CSGTILE_REQUIRE_AJV="${CSGTILE_REQUIRE_AJV:-1}"
export CSGTILE_GLTF_VALIDATOR_DIR="$PWD/build/npm/node_modules/gltf-validator"
export CSGTILE_REQUIRE_GLTF_VALIDATOR="${CSGTILE_REQUIRE_GLTF_VALIDATOR:-1}"
# S3 fetch tests: @20minutes/s3rver (verifies SigV4 signatures), same install.
export CSGTILE_S3RVER_DIR="$PWD/build/npm/node_modules/@20minutes/s3rver"
export CSGTILE_REQUIRE_S3RVER="${CSGTILE_REQUIRE_S3RVER:-1}"
# The run report in headless Chromium (tests/cli/report_chromium.py): chromium from setup.sh,
# puppeteer-core and the 3D view compiled in (three, esbuild) from the same install.
export CSGTILE_PUPPETEER_DIR="$PWD/build/npm/node_modules/puppeteer-core"
export CSGTILE_REQUIRE_REPORT_VIEWER="${CSGTILE_REQUIRE_REPORT_VIEWER:-1}"
# The seeded Boolean property tests run ten times their default case counts here (4 000 box
# pairs, 400 mixed-primitive pairs); the sanitizer stage keeps the defaults.
CSGTILE_PROPERTY_SCALE="${CSGTILE_PROPERTY_SCALE:-10}" ctest --test-dir build --output-on-failure -j"$jobs"

if [ "${CSGTILE_SKIP_TIDY:-0}" != 1 ]; then
  echo "== clang-tidy: every source of kernel/, geo/, config/ and worker/"
  # A unit whose preprocessed text was found clean before (same tool, same .clang-tidy) is not
  # analysed again (tests/boundaries/check_tidy.py; cache in ~/.cache/csgtile-tidy): a cold run
  # is about 22 minutes on 2 cores, a run after a small change a few.
  tests/boundaries/check_tidy.sh build
fi

if [ "${CSGTILE_SKIP_SANITIZE:-0}" != 1 ]; then
  echo "== ASan+UBSan build: kernel, assembly, geo, fit, config and CLI tests"
  # The SIGTERM grace tests wait out 90 s of grace periods each: the optimised stage runs them;
  # under the sanitizers they would add three minutes, mostly of waiting, to a stage near CI's
  # 90-minute budget. So do the quality measurements on the shared data (label quality: the
  # Fit4CAD, gate, real-tile and city-quality scores, about eight minutes under the
  # sanitizers): they run the fit and the city pipeline that the fit and cli.run.city* tests
  # run here too, on more points, and their figures are checked by the optimised stage.
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCSGTILE_WERROR=ON \
        -DCSGTILE_SANITIZE=ON -DCSGTILE_BUILD_TESTS=ON \
        -DCSGTILE_REPORT_NPM_DIR="$PWD/build/npm/node_modules" >/dev/null
  cmake --build build-asan -j"$jobs"
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir build-asan --output-on-failure -j"$jobs" -L 'kernel|assembly|geo|fit|config|cli|boundaries' \
          -LE quality -E 'sigterm_grace'
fi

if [ "${CSGTILE_SKIP_FUZZ:-0}" != 1 ]; then
  echo "== libFuzzer targets (bounded runs)"
  cmake -S . -B build-fuzz -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
        -DCSGTILE_FUZZ=ON -DCSGTILE_BUILD_TESTS=OFF >/dev/null
  # Only the fuzz targets (and the libraries they parse with) need this instrumented build.
  cmake --build build-fuzz -j"$jobs" --target native_reader_fuzz native_reader_fuzz_seeds \
        las_reader_fuzz las_reader_fuzz_seeds laz_reader_fuzz laz_reader_fuzz_seeds
  ctest --test-dir build-fuzz --output-on-failure -L fuzz
fi
