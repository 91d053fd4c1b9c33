#!/usr/bin/env bash
# Multi-host rehearsal on one machine: PostgreSQL in one network namespace, three
# `csgtile worker` processes in three others, joined by veth pairs to a bridge in a fifth
# namespace (10.231.0.0/24, no other routes: nothing leaves the machine). A city run goes to
# completion; mid-run, the link of a worker that has just claimed a heavy job is cut
# (`ip link set down` on its bridge port). Its lease expires, another worker claims and
# completes the job, and when the link returns the cut worker's renewal is refused (fencing):
# it discards its outcome and goes on with other jobs. Then the queue's rows, the workers'
# logs and the run manifest must show every job done exactly once.
#
# Usage: deploy/rehearsal/netns-rehearsal.sh [CSGTILE]      (as root; default: build/csgtile)
# Environment: REHEARSAL_KEEP=1 keeps the temporary directory (logs, queue dump, outputs).
# Prints the figures as one JSON object on the last line of stdout. Exit 0: passed;
# 1: failed (the reason on stderr); 77: cannot run here (not root, no `ip netns`, no
# PostgreSQL 15), with the reason.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
binary="$(realpath "${1:-$repo/build/csgtile}")"
pgbin=/usr/lib/postgresql/15/bin

skip() { echo "netns-rehearsal: SKIP: $*" >&2; exit 77; }
[ "$(id -u)" -eq 0 ] || skip "needs root (network namespaces, veth, bridge)"
command -v ip >/dev/null || skip "iproute2 (ip) is not installed"
if [ ! -x "$pgbin/postgres" ]; then
  # deploy/run-tests.sh sets CSGTILE_REQUIRE_POSTGRES=1: setup.sh installed it, so it must run.
  [ "${CSGTILE_REQUIRE_POSTGRES:-0}" = 1 ] && { echo "netns-rehearsal: PostgreSQL 15 is missing" >&2; exit 1; }
  skip "PostgreSQL 15 is not installed (apt-get install postgresql-15)"
fi
id postgres >/dev/null 2>&1 || skip "no postgres user (initdb refuses root)"
command -v python3 >/dev/null || skip "python3 is not installed"
[ -x "$binary" ] || { echo "netns-rehearsal: no csgtile binary at $binary" >&2; exit 1; }

# Leftovers of a rehearsal killed without its cleanup (e.g. SIGKILL at a test timeout): its
# namespaces are named after its pid, its work directory holds that pid in "owner".
for owner in /tmp/csgtile-rehearsal.*/owner; do
  [ -f "$owner" ] || continue
  old_pid="$(cat "$owner")"
  # Still running (a zombie has an empty command line; another program may reuse the pid).
  { tr '\0' ' ' <"/proc/$old_pid/cmdline"; } 2>/dev/null | grep -q netns-rehearsal && continue
  old_work="$(dirname "$owner")"
  # Its controller and workers (pids in "pids"), if they still run with its work directory.
  for pid in $(cat "$old_work/controller" "$old_work/pids" 2>/dev/null); do
    if { tr '\0' ' ' <"/proc/$pid/cmdline"; } 2>/dev/null | grep -q "$old_work"; then
      kill -KILL "$pid" 2>/dev/null || true
    fi
  done
  if [ -f "$old_work/pg/data/postmaster.pid" ]; then
    runuser -u postgres -- "$pgbin/pg_ctl" -D "$old_work/pg/data" -m immediate stop >/dev/null 2>&1 || true
  fi
  for ns in $(ip netns list | awk '{print $1}' | grep "^csgt$old_pid-"); do ip netns del "$ns"; done
  rm -rf "$old_work"
done

prefix="csgt$$"
sw="$prefix-sw"
hosts=(pg w1 w2 w3)
declare -A address=([pg]=10.231.0.1 [w1]=10.231.0.11 [w2]=10.231.0.12 [w3]=10.231.0.13)
probe="$prefix-probe"
ip netns add "$probe" 2>/dev/null || skip "ip netns add fails here (no CAP_SYS_ADMIN or no netns support)"
ip netns del "$probe"

work="$(mktemp -d /tmp/csgtile-rehearsal.XXXXXX)"
chmod 755 "$work"
echo $$ >"$work/owner"
control=""
pg_started=0
cleanup() {
  local rc=$?
  set +e
  # The controller, then the workers it started (their pids in $work/pids).
  [ -n "$control" ] && kill -KILL "$control" 2>/dev/null && wait "$control" 2>/dev/null
  if [ -f "$work/pids" ]; then
    while read -r pid; do
      # Only while it is still one of ours (its command line names the work directory).
      { tr '\0' ' ' <"/proc/$pid/cmdline"; } 2>/dev/null | grep -q "$work" && kill -KILL "$pid" 2>/dev/null
    done <"$work/pids"
  fi
  if [ "$pg_started" = 1 ]; then
    ip netns exec "$prefix-pg" runuser -u postgres -- "$pgbin/pg_ctl" -D "$work/pg/data" \
      -m immediate stop >/dev/null 2>&1
  fi
  for h in "${hosts[@]}"; do ip netns del "$prefix-$h" 2>/dev/null; done
  ip netns del "$sw" 2>/dev/null
  if [ "${REHEARSAL_KEEP:-0}" = 1 ]; then
    echo "netns-rehearsal: kept $work" >&2
  else
    rm -rf "$work"
  fi
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# 1. The network: a bridge in its own namespace, one veth pair per host.
ip netns add "$sw"
ip -n "$sw" link set lo up
ip -n "$sw" link add br0 type bridge
ip -n "$sw" link set br0 up
for h in "${hosts[@]}"; do
  ns="$prefix-$h"
  ip netns add "$ns"
  ip -n "$ns" link set lo up
  ip -n "$sw" link add "port-$h" type veth peer name eth0 netns "$ns"
  ip -n "$sw" link set "port-$h" master br0 up
  ip -n "$ns" addr add "${address[$h]}/24" dev eth0
  ip -n "$ns" link set eth0 up
done

# 2. PostgreSQL 15 in the pg namespace, listening on its bridge address only (plus a Unix
# socket in the work directory, which the controller uses: sockets are not network).
password="rehearsal-$RANDOM$RANDOM"
mkdir -p "$work/pg"
printf '%s\n' "$password" >"$work/pg/pwfile"
chown -R postgres "$work/pg"
runuser -u postgres -- "$pgbin/initdb" -D "$work/pg/data" -U csgtile -A scram-sha-256 \
  --pwfile="$work/pg/pwfile" >"$work/pg/initdb.log" 2>&1 \
  || { cat "$work/pg/initdb.log" >&2; exit 1; }
echo "host all csgtile 10.231.0.0/24 scram-sha-256" >>"$work/pg/data/pg_hba.conf"
ip netns exec "$prefix-pg" runuser -u postgres -- "$pgbin/pg_ctl" -D "$work/pg/data" \
  -o "-p 5432 -k $work/pg -c listen_addresses=${address[pg]}" -l "$work/pg/log" -w start >/dev/null \
  || { cat "$work/pg/log" >&2; exit 1; }
pg_started=1
export PGPASSWORD="$password"
psql -h "$work/pg" -p 5432 -U csgtile -d postgres -qAt -c "CREATE DATABASE csgtile" >/dev/null
# Every worker namespace reaches the database through the bridge.
for h in w1 w2 w3; do
  ip netns exec "$prefix-$h" "$pgbin/pg_isready" -h "${address[pg]}" -p 5432 -t 5 >/dev/null \
    || { echo "netns-rehearsal: $h cannot reach PostgreSQL at ${address[pg]}" >&2; exit 1; }
done

# 3. The city: shifted copies of the sample scenes and of the synthetic timber gate.
mapfile -t inputs < <(python3 "$here/make_inputs.py" "$binary" "$repo" "$work/inputs" \
                        "${REHEARSAL_LIGHT_COPIES:-4}" "${REHEARSAL_HEAVY_COPIES:-2}")
config="$work/rehearsal.yaml"
{
  echo "run:"
  echo "  name: rehearsal"
  echo "  inputs:"
  for i in "${inputs[@]}"; do echo "    - $i"; done
  echo "  output: $work/out"   # one file system: stands for the volume the workers share
  echo "  threads: 1"
  echo "queue:"
  echo "  backend: postgres"
  echo "  postgres_dsn: \"host=${address[pg]} port=5432 dbname=csgtile user=csgtile\""
  echo "  postgres_sslmode: disable"
  echo "  lease_seconds: 3"
  echo "  max_attempts: 5"
  echo "log:"
  echo "  format: json"
} >"$config"

# 4. The run, the cut and the checks (rehearsal_control.py); it writes the pids of the
# workers it starts to $work/pids, for the cleanup above.
export CSGTILE_PG_PASSWORD="$password"
python3 "$here/rehearsal_control.py" --binary "$binary" --config "$config" --work "$work" \
  --prefix "$prefix" --switch "$sw" --socket "$work/pg" &
control=$!
echo "$control" >"$work/controller"
status=0
wait "$control" || status=$?
control=""
exit "$status"
