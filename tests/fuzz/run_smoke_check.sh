#!/bin/sh
# Checks run_smoke.sh with stand-in fuzzers: a failing session keeps its exit code and prints
# each input it left (base64, decodable to the same bytes); a clean one prints none.
# Usage: run_smoke_check.sh SCRATCH_DIR
set -eu
here=$(cd "$(dirname "$0")" && pwd)
dir=$1
rm -rf "$dir"
mkdir -p "$dir"
cat > "$dir/crashing" <<'FUZZ'
#!/bin/sh
prefix=${1#-artifact_prefix=}
echo "INFO: Seed: 1234"
printf 'LASF\001\002hostile' > "${prefix}crash-0123"
exit 77
FUZZ
cat > "$dir/clean" <<'FUZZ'
#!/bin/sh
echo "INFO: Seed: 99"
exit 0
FUZZ
chmod +x "$dir/crashing" "$dir/clean"
set +e
sh "$here/run_smoke.sh" "$dir/crashing" "$dir/a" -runs=1 > "$dir/crashing.log" 2>&1
rc=$?
set -e
[ "$rc" -eq 77 ] || { echo "exit $rc, want 77"; cat "$dir/crashing.log"; exit 1; }
grep -q "INFO: Seed: 1234" "$dir/crashing.log"
grep -q "== crash-0123: 13 bytes" "$dir/crashing.log"
grep -A1 "== crash-0123" "$dir/crashing.log" | tail -1 | base64 -d > "$dir/replayed"
printf 'LASF\001\002hostile' | cmp - "$dir/replayed"
sh "$here/run_smoke.sh" "$dir/clean" "$dir/b" > "$dir/clean.log" 2>&1
! grep -q "base64" "$dir/clean.log"
echo "run_smoke.sh: failing inputs printed and replayable; clean sessions quiet"
