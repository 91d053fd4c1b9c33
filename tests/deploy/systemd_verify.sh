#!/bin/sh
# systemd-analyze verify on deploy/systemd's units. verify checks that ExecStart's program
# exists, so the units are checked as installed with the built binary in /usr/local/bin's
# place. Fails on any warning that names one of the units. Exit 77 = skipped.
# Usage: systemd_verify.sh REPO_DIR CSGTILE
set -eu
repo="$1"
binary="$(realpath "$2")"
command -v systemd-analyze >/dev/null || { echo "SKIP: systemd-analyze is not installed"; exit 77; }
units="$(mktemp -d)"
trap 'rm -rf "$units"' EXIT
for f in "$repo"/deploy/systemd/*.service "$repo"/deploy/systemd/*.timer; do
  sed "s#/usr/local/bin/csgtile#$binary#g" "$f" >"$units/$(basename "$f")"
done
cd "$units"
log="$(SYSTEMD_LOG_LEVEL=notice systemd-analyze verify --man=no ./*.service ./*.timer 2>&1)" \
  || { echo "FAIL: systemd-analyze verify:"; echo "$log"; exit 1; }
if echo "$log" | grep -q 'csgtile'; then
  echo "FAIL: systemd-analyze verify warns:"; echo "$log"; exit 1
fi
echo "ok: systemd-analyze verify $(ls | tr "\n" " ")"
