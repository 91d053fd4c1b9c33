#!/bin/sh
# Every C++ source and header under ROOT is as clang-format (the repository's .clang-format)
# writes it. Usage: check_format.sh ROOT [CLANG_FORMAT]. Files of the boundary checks'
# fixtures are left out (they are deliberately odd). Exit 1 naming the files that differ.
root=$1
tool=${2:-clang-format}
if ! command -v "$tool" >/dev/null 2>&1; then
  echo "clang-format not found ('$tool'): apt-get install clang-format (deploy/setup.sh installs it)" >&2
  exit 1
fi
cd "$root" || exit 1
if [ -d .git ]; then
  files=$(git ls-files -- '*.cpp' '*.h' | grep -v '^tests/boundaries/fixture')
else
  files=$(find . -name '*.cpp' -o -name '*.h' | grep -v '/build' | grep -v 'tests/boundaries/fixture')
fi
bad=0
for f in $files; do
  if ! "$tool" --dry-run --Werror "$f" >/dev/null 2>&1; then
    echo "not formatted: $f (clang-format -i $f)"
    bad=1
  fi
done
[ "$bad" -eq 0 ] && echo "$(echo "$files" | wc -w) files formatted"
exit $bad
