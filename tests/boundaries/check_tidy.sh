#!/bin/sh
# clang-tidy (the repository's .clang-tidy, warnings as errors) on every translation unit of
# kernel/, geo/, config/ and worker/ that BUILD_DIR's compile_commands.json lists, or on the
# FILES given. Usage: check_tidy.sh BUILD_DIR [FILES...]. Jobs: CSGTILE_TIDY_JOBS (default: the
# cores). Exit 1 with every warning printed; the headers of those directories are checked
# through the units that include them (HeaderFilterRegex).
build=$(cd "$1" && pwd)
shift
tool=${CLANG_TIDY:-clang-tidy}
if ! command -v "$tool" >/dev/null 2>&1; then
  echo "clang-tidy not found ('$tool'): apt-get install clang-tidy (deploy/setup.sh installs it)" >&2
  exit 1
fi
root=$(cd "$(dirname "$0")/../.." && pwd)
if [ ! -f "$build/compile_commands.json" ]; then
  echo "$build/compile_commands.json missing: configure with CMake first" >&2
  exit 1
fi
list=$(mktemp)
out=$(mktemp -d)
trap 'rm -rf "$list" "$out"' EXIT
if [ $# -gt 0 ]; then
  for f in "$@"; do echo "$f"; done > "$list"
else
  python3 - "$build/compile_commands.json" "$root" > "$list" <<'PY'
import json, os, sys
root = sys.argv[2]
units = set()
for entry in json.load(open(sys.argv[1])):
    path = os.path.realpath(os.path.join(entry["directory"], entry["file"]))
    rel = os.path.relpath(path, root)
    if rel.split(os.sep)[0] in ("kernel", "geo", "config", "worker"):
        units.add(rel)
print("\n".join(sorted(units)))
PY
fi
jobs=${CSGTILE_TIDY_JOBS:-$(nproc)}
# -Wno-restrict and the like are GCC's: clang must not count them as errors.
cd "$root" && xargs -P "$jobs" -I{} sh -c \
  '"$0" -p "$1" --quiet --extra-arg=-Wno-unknown-warning-option "$2" > "$3/$(echo "$2" | tr / _).log" 2>&1 || true' \
  "$tool" "$build" {} "$out" < "$list"
# Only diagnostics count (clang-tidy also prints how many warnings it suppressed).
grep -h -E '(warning|error):' "$out"/*.log | sort -u > "$out/all"
if [ -s "$out/all" ]; then
  cat "$out/all"
  echo "clang-tidy: $(wc -l < "$out/all") diagnostics in $(wc -l < "$list") units" >&2
  exit 1
fi
echo "clang-tidy: $(wc -l < "$list") units clean"
