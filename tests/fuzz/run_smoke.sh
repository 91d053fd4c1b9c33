#!/bin/sh
# A bounded libFuzzer session that leaves what is needed to replay a failure in the log:
# the fuzzer prints its seed ("INFO: Seed: N"); its crash, leak, timeout and OOM inputs are
# written to ARTIFACTS (emptied first) and, when the session fails, each is printed as base64
# (`base64 -d > input && FUZZER input` replays it).
# Usage: run_smoke.sh FUZZER ARTIFACTS [libFuzzer arguments...]
set -u
fuzzer=$1
artifacts=$2
shift 2
rm -rf "$artifacts"
mkdir -p "$artifacts"
"$fuzzer" -artifact_prefix="$artifacts/" "$@"
rc=$?
if [ "$rc" -ne 0 ]; then
  for input in "$artifacts"/*; do
    [ -f "$input" ] || continue
    echo "== $(basename "$input"): $(wc -c < "$input") bytes, base64 (decode and pass it to $(basename "$fuzzer") to replay):"
    base64 -w 0 "$input"
    echo
  done
fi
exit "$rc"
