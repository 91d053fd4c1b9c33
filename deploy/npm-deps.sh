#!/usr/bin/env bash
# Installs the npm packages csgtile's build and tests use into build/npm (run from the
# repository's root). npm runs only when a package is missing or has another version.
#   deploy/npm-deps.sh viewer   three and esbuild: the run report's 3D view, bundled by esbuild
#                               when CMake configures (so this runs before it); what
#                               deploy/run-demo.sh needs
#   deploy/npm-deps.sh all      the viewer's, plus the validators and servers of the tests:
#                               ajv-cli (CityJSON schema), the Khronos glTF validator,
#                               @20minutes/s3rver (S3 fetch), puppeteer-core (the report in
#                               Debian's chromium); what deploy/run-tests.sh needs
# Node.js and npm come from deploy/setup.sh.
set -euo pipefail
viewer=(three@0.187.0 esbuild@0.28.2)
tests=(ajv@8 ajv-formats@3 ajv-cli@5 gltf-validator@2.0.0-dev.3.10 @20minutes/s3rver@5
       puppeteer-core@24)
case "${1:-}" in
  viewer) wanted=("${viewer[@]}") ;;
  all) wanted=("${viewer[@]}" "${tests[@]}") ;;
  *) echo "usage: deploy/npm-deps.sh viewer|all" >&2; exit 64 ;;
esac
# name@version → present with that version (or that major version when only a major is given).
if ! node -e '
  const dir = process.argv[1];
  for (const spec of process.argv.slice(2)) {
    const at = spec.lastIndexOf("@");
    const name = spec.slice(0, at), want = spec.slice(at + 1);
    const v = require(dir + "/node_modules/" + name + "/package.json").version;
    if (v !== want && v.split(".")[0] !== want) process.exit(1);
  }' "$PWD/build/npm" "${wanted[@]}" 2>/dev/null; then
  npm install --no-audit --no-fund --prefix build/npm "${wanted[@]}"
fi
