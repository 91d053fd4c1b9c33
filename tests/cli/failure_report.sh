#!/bin/sh
# How every command that gathers a JSON report says it failed (worker/src/cli.cpp,
# report_failure): with --json one JSON line on stdout whose "error" is "<code name>: <message>"
# and nothing on stderr; without it "csgtile <command>: <message>" on stderr and nothing on
# stdout; the exit code of the code (io: 74) either way. Usage: failure_report.sh CSGTILE WORK
bin=$1
work=$2
rm -rf "$work" && mkdir -p "$work" || exit 1
missing=/nonexistent/tile.las
fails=0
check() {  # NAME ARGS...: the command must fail with io on a missing input
  name=$1
  shift
  "$bin" "$name" "$@" --json >"$work/out" 2>"$work/err"
  rc=$?
  if [ $rc -ne 74 ] || [ -s "$work/err" ] ||
     ! python3 -c 'import json,sys; l=open(sys.argv[1]).read().splitlines(); assert len(l)==1; e=json.loads(l[0])["error"]; assert e.startswith("io: ") and "/nonexistent/" in e, e' "$work/out"; then
    echo "FAIL $name --json: exit $rc, stdout: $(cat "$work/out"), stderr: $(cat "$work/err")"
    fails=1
  fi
  "$bin" "$name" "$@" >"$work/out" 2>"$work/err"
  rc=$?
  if [ $rc -ne 74 ] || [ -s "$work/out" ] || ! grep -q "^csgtile $name: .*/nonexistent/" "$work/err"; then
    echo "FAIL $name: exit $rc, stdout: $(cat "$work/out"), stderr: $(cat "$work/err")"
    fails=1
  fi
}
check info "$missing"
check tile "$missing" --size 10 --out "$work/tiles"
check fit "$missing" --out "$work/fit.json"
check query /nonexistent/index.gpkg --relations x
[ $fails -eq 0 ] && echo "failure reports: the same shape for info, tile, fit and query"
exit $fails
