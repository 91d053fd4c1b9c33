#!/usr/bin/env python3
"""Chaos: N jobs, 4 `csgtile worker` processes sharing one queue, a random worker killed with
SIGKILL every few seconds (and restarted, as a supervisor would), one worker frozen with
SIGSTOP past its lease and resumed after others took its job over, and — on PostgreSQL — the
server restarted twice mid-run (`pg_ctl -m immediate`: a crash). Then:
  * 0 jobs lost: every job done or dead (and none dead here: the jobs are healthy, and the
    attempt budget covers the kills);
  * 0 duplicate manifest entries, every job once;
  * every published model's SHA-256 matches its manifest entry;
  * the frozen worker's stale outcome was refused (fencing): it logs lease_lost, never done,
    for that job.
Prints one JSON line of figures.
Usage: chaos_workers.py CSGTILE WORKDIR sqlite|postgres [JOBS]"""
import hashlib
import json
import os
import random
import shutil
import signal
import socket
import subprocess
import sys
import time

binary, work, backend = sys.argv[1], sys.argv[2], sys.argv[3]
jobs = int(sys.argv[4]) if len(sys.argv) > 4 else 500
rng = random.Random(7)
shutil.rmtree(work, ignore_errors=True)
os.makedirs(f"{work}/scenes")

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from worker_jobs import write_jobs  # noqa: E402

inputs = write_jobs(f"{work}/scenes", jobs)

pg = None
queue_yaml = "queue:\n  lease_seconds: 2\n  max_attempts: 20\n"
if backend == "postgres":
    pg_bin = "/usr/lib/postgresql/15/bin"
    if not os.path.exists(f"{pg_bin}/initdb"):
        if os.environ.get("CSGTILE_REQUIRE_POSTGRES") == "1":
            sys.exit("PostgreSQL 15 is required (CSGTILE_REQUIRE_POSTGRES=1) but not installed")
        print("skip: PostgreSQL 15 not installed")
        sys.exit(0)
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    pg = f"{work}/pg"
    os.makedirs(pg)
    as_pg = ["runuser", "-u", "postgres", "--"] if os.geteuid() == 0 else []
    if as_pg:
        shutil.chown(pg, "postgres")
    subprocess.run(as_pg + [f"{pg_bin}/initdb", "-D", f"{pg}/data", "-A", "trust", "-U", "csgtile"],
                   check=True, capture_output=True)

    def pg_ctl(*args):
        subprocess.run(as_pg + [f"{pg_bin}/pg_ctl", "-D", f"{pg}/data", *args], check=True,
                       capture_output=True)

    def pg_start():
        pg_ctl("-o", f"-p {port} -k {pg} -c listen_addresses=127.0.0.1", "-l", f"{pg}/log", "-w", "start")

    pg_start()
    queue_yaml += (f"  backend: postgres\n  postgres_dsn: \"host=127.0.0.1 port={port} "
                   f"dbname=postgres user=csgtile connect_timeout=5\"\n")

config = f"{work}/run.yaml"
with open(config, "w") as f:
    f.write(f"run:\n  name: chaos\n  inputs:\n" + "".join(f"    - {p}\n" for p in inputs) +
            f"  output: {work}/out\n{queue_yaml}log:\n  format: json\n")

figures = {"backend": backend, "jobs": jobs, "kills": 0, "pg_restarts": 0}
try:
    p = subprocess.run([binary, "enqueue", config, "--json"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr

    logs = []

    def spawn(i):
        log = open(f"{work}/worker-{i}-{len(logs)}.log", "w")
        logs.append(log.name)
        return subprocess.Popen([binary, "worker", config, "--exit-when-idle", "--json"],
                                stdout=subprocess.DEVNULL, stderr=log)

    workers = [spawn(i) for i in range(4)]
    start = time.time()
    next_kill = start + 2.0
    restarts_at = [start + 4.0, start + 9.0] if pg else []
    frozen = None  # (index, pid, log, when)
    while time.time() - start < 600:
        time.sleep(0.2)
        now = time.time()
        if frozen is None and now - start > 3.0:
            i = 0
            os.kill(workers[i].pid, signal.SIGSTOP)
            frozen = (i, workers[i].pid, logs[-4 + i] if len(logs) >= 4 else logs[i], now)
            figures["sigstop"] = 1
        if frozen and frozen[3] > 0 and now - frozen[3] > 6.0:  # 3 leases later
            os.kill(frozen[1], signal.SIGCONT)
            frozen = (frozen[0], frozen[1], frozen[2], -1)
        if restarts_at and now >= restarts_at[0]:
            restarts_at.pop(0)
            pg_ctl("-m", "immediate", "stop")
            time.sleep(1.0)
            pg_start()
            figures["pg_restarts"] += 1
        if now >= next_kill:
            next_kill = now + rng.uniform(1.5, 3.0)
            candidates = [i for i in range(4) if workers[i].poll() is None and
                          not (frozen and frozen[3] > 0 and i == frozen[0])]
            if candidates:
                i = rng.choice(candidates)
                workers[i].kill()
                workers[i].wait()
                figures["kills"] += 1
                workers[i] = spawn(i)
        # A worker that exited (idle, or on a queue error while PostgreSQL was down) is
        # restarted while the run is unfinished, as a supervisor would.
        status = subprocess.run([binary, "status", config, "--json"], capture_output=True, text=True)
        done = status.returncode == 0 and json.loads(status.stdout.strip().splitlines()[-1])["finished"]
        if done and (not restarts_at) and (frozen is None or frozen[3] < 0):
            break
        for i in range(4):
            if workers[i].poll() is not None and not done:
                workers[i] = spawn(i)
    figures["seconds"] = round(time.time() - start, 1)
    for w in workers:
        try:
            w.wait(timeout=120)
        except subprocess.TimeoutExpired:
            w.kill()
    # Publish once more from a clean worker (idempotent: same bytes as any earlier publish).
    p = subprocess.run([binary, "worker", config, "--exit-when-idle", "--json"], capture_output=True, text=True)
    assert p.returncode == 0, (p.returncode, p.stderr[-3000:])

    manifest_path = f"{work}/out/runs/chaos/manifest.json"
    manifest = json.load(open(manifest_path))
    keys = [j["key"] for j in manifest["jobs"]]
    figures["done"] = len(keys)
    figures["dead"] = len(manifest["dead"])
    figures["duplicates"] = len(keys) - len(set(keys))
    assert figures["duplicates"] == 0, "duplicate manifest entries"
    assert len(keys) + len(manifest["dead"]) == jobs, ("lost jobs", len(keys), len(manifest["dead"]))
    assert not manifest["dead"], manifest["dead"][:5]
    mismatches = 0
    run_dir = f"{work}/out/runs/chaos"
    for job in manifest["jobs"]:
        model = job["result"]["model"]
        data = open(f"{run_dir}/{model['key']}", "rb").read()
        mismatches += hashlib.sha256(data).hexdigest() != model["sha256"] or len(data) != model["bytes"]
    figures["hash_mismatches"] = mismatches
    assert mismatches == 0
    # The frozen worker: whatever it was running when frozen was taken over; when it woke,
    # its outcome was refused (lease_lost), and it never logged "done" for a job another
    # worker completed after the takeover.
    lost = 0
    done_by = {}
    for name in logs:
        for line in open(name):
            if not line.startswith("{"):
                continue
            entry = json.loads(line)
            if entry.get("component") == "job" and entry.get("message") == "done":
                done_by.setdefault(entry["job"], []).append(name)
            if "lease" in entry.get("message", "") and "lost" in entry.get("message", ""):
                lost += 1
    figures["lease_lost_logged"] = lost
    twice = {k: v for k, v in done_by.items() if len(v) > 1}
    figures["jobs_logged_done_twice"] = len(twice)
    assert not twice, list(twice.items())[:3]
    print(json.dumps(figures))
finally:
    for w in locals().get("workers", []):
        if w.poll() is None:
            try:
                os.kill(w.pid, signal.SIGCONT)
            except ProcessLookupError:
                pass
            w.kill()
    if pg:
        try:
            pg_ctl("-m", "immediate", "stop")
        except Exception:
            pass
