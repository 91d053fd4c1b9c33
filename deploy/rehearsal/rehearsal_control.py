#!/usr/bin/env python3
"""The run phase of netns-rehearsal.sh (which builds the namespaces and the database, and
cleans up): enqueue, three workers in three namespaces, a link cut mid-job, the checks, the
figures. The queue is watched through PostgreSQL's Unix socket (psql), not the network.

Exit 0 when every check passes (figures as one JSON line on stdout), 1 otherwise."""
import argparse
import json
import os
import subprocess
import sys
import time

args = argparse.ArgumentParser()
args.add_argument("--binary", required=True)
args.add_argument("--config", required=True)
args.add_argument("--work", required=True)
args.add_argument("--prefix", required=True)
args.add_argument("--switch", required=True)
args.add_argument("--socket", required=True)
args.add_argument("--timeout", type=float, default=170.0)
opts = args.parse_args()
WORKERS = ["w1", "w2", "w3"]
start = time.monotonic()
problems = []


def log(message):
    print(f"netns-rehearsal: {time.monotonic() - start:6.1f}s {message}", file=sys.stderr, flush=True)


def fail(message):
    log("FAILED: " + message)
    sys.exit(1)


def sql(query):
    """Rows of a query as lists of strings (psql over the Unix socket)."""
    out = subprocess.run(["psql", "-h", opts.socket, "-p", "5432", "-U", "csgtile", "-d", "csgtile",
                          "-qAtX", "-F", "\t", "-c", query],
                         capture_output=True, text=True, timeout=30)
    if out.returncode != 0:
        fail(f"psql: {out.stderr.strip()}")
    return [line.split("\t") for line in out.stdout.splitlines() if line]


def in_namespace(host, *command):
    return ["ip", "netns", "exec", f"{opts.prefix}-{host}", *command]


def set_link(host, state):
    subprocess.run(["ip", "-n", opts.switch, "link", "set", f"port-{host}", state], check=True)


def check(condition, message):
    if not condition:
        problems.append(message)
        log("check failed: " + message)


# 1. Enqueue from a worker host, over the network.
enqueue = subprocess.run(in_namespace("w1", opts.binary, "enqueue", opts.config, "--json"),
                         capture_output=True, text=True, timeout=60)
if enqueue.returncode != 0:
    fail(f"enqueue exited {enqueue.returncode}: {enqueue.stderr.strip()[-2000:]}")
jobs = json.loads(enqueue.stdout.strip().splitlines()[-1])["added"]
log(f"enqueued {jobs} jobs")

# 2. Three workers; `ip netns exec` execs the command, so each pid is the worker's own, and
# the worker's id in the queue is "local-<pid>".
workers = {}
with open(os.path.join(opts.work, "pids"), "w") as pids:
    for host in WORKERS:
        err = open(os.path.join(opts.work, f"{host}.log"), "w")
        out = open(os.path.join(opts.work, f"{host}.out"), "w")
        p = subprocess.Popen(in_namespace(host, opts.binary, "worker", opts.config, "--exit-when-idle",
                                          "--json"), stdout=out, stderr=err)
        workers[host] = p
        pids.write(f"{p.pid}\n")
        pids.flush()
host_of = {f"local-{p.pid}": host for host, p in workers.items()}
run_started = time.monotonic()


def worker_log(host):
    lines = []
    with open(os.path.join(opts.work, f"{host}.log")) as f:
        for line in f:
            try:
                lines.append(json.loads(line))
            except json.JSONDecodeError:
                pass  # a line being written
    return lines


def wait_for(what, predicate, timeout=60.0, period=0.05):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        if all(p.poll() is not None for p in workers.values()):
            fail(f"workers exited while waiting for {what}")
        time.sleep(period)
    fail(f"timed out after {timeout:.0f} s waiting for {what}")


# 3. The cut: a heavy (gate) job on its first attempt, claimed since the previous poll (so
# most of the job, and its first renewal, are still ahead of it). Before the first poll nothing
# was running (the workers started just now): a worker starts in tens of milliseconds, and may
# claim a gate job before the first poll.
running_before = set()


def just_claimed_heavy():
    global running_before
    rows = sql("SELECT key, worker, extract(epoch FROM lease_expires - now()) FROM csgtile_jobs "
               "WHERE state = 'running' AND attempts = 1 AND key LIKE '%/gate-%' ORDER BY id")
    fresh = [r for r in rows if r[0] not in running_before and r[1] in host_of]
    running_before = {r[0] for r in rows}
    return fresh[0] if fresh else None


key, cut_worker, lease_left = wait_for("a heavy job to be claimed", just_claimed_heavy)
cut_host = host_of[cut_worker]
set_link(cut_host, "down")
t_cut = time.monotonic()
t_expiry = t_cut + float(lease_left)  # no renewal gets through after the cut
log(f"cut {cut_host} ({cut_worker}) running {key.split(':')[-1]} (lease left {float(lease_left):.2f} s)")


# 4. Another worker takes the job over once the lease has expired.
def reclaimed():
    worker, attempts = sql(f"SELECT worker, attempts FROM csgtile_jobs WHERE key = '{key}'")[0]
    return (worker, attempts) if worker != cut_worker and int(attempts) >= 2 else None


new_worker, attempts = wait_for("the job to be reclaimed", reclaimed, timeout=60)
t_reclaim = time.monotonic()
reclaim_host = host_of.get(new_worker, new_worker)
log(f"{reclaim_host} reclaimed it (attempt {attempts}, {t_reclaim - t_cut:.2f} s after the cut)")
# The new holder completes it while the cut worker is still away.
wait_for("the reclaimed job to be done",
         lambda: sql(f"SELECT state FROM csgtile_jobs WHERE key = '{key}'")[0][0] == "done", timeout=90)
t_done = time.monotonic()
log(f"{reclaim_host} completed it ({t_done - t_cut:.2f} s after the cut)")

# 5. The link returns; the cut worker's renewal finds the lease gone and discards its outcome.
set_link(cut_host, "up")
t_restore = time.monotonic()
log(f"link of {cut_host} restored")


def discarded():
    return next((line for line in worker_log(cut_host)
                 if line.get("message") == "lease lost; outcome discarded" and line.get("job") == key),
                None)


discard_line = wait_for("the cut worker to discard its outcome", discarded, timeout=120, period=0.2)
t_discard = time.monotonic()
log(f"{cut_host} discarded its outcome ({t_discard - t_restore:.2f} s after the link returned)")

# 6. Every worker finishes the run and exits 0.
deadline = time.monotonic() + opts.timeout
for host, p in workers.items():
    try:
        p.wait(timeout=max(1.0, deadline - time.monotonic()))
    except subprocess.TimeoutExpired:
        fail(f"{host} did not finish within {opts.timeout:.0f} s")
t_end = time.monotonic()
for host, p in workers.items():
    check(p.returncode == 0, f"{host} exited {p.returncode}")
    summary_lines = open(os.path.join(opts.work, f"{host}.out")).read().strip().splitlines()
    check(bool(summary_lines), f"{host} printed no summary")
    if summary_lines:
        summary = json.loads(summary_lines[-1])
        check(summary["done"] == jobs and summary["unfinished"] == 0 and summary["dead"] == 0,
              f"{host} summary {summary}")

# 7. The checks: queue rows, logs, manifest.
rows = sql("SELECT key, state, attempts, worker FROM csgtile_jobs ORDER BY id")
check(len(rows) == jobs, f"{len(rows)} rows in the queue for {jobs} jobs")
check(all(r[1] == "done" for r in rows), f"not all done: {[r for r in rows if r[1] != 'done']}")
target = next(r for r in rows if r[0] == key)
check(int(target[2]) == 2 and target[3] == new_worker,
      f"the cut job should be done by {new_worker} on attempt 2: {target}")
others = [r for r in rows if r[0] != key]
check(all(int(r[2]) == 1 for r in others), f"jobs run more than once: {[r for r in others if r[2] != '1']}")
done_lines = {host: [l["job"] for l in worker_log(host) if l.get("component") == "job"
                     and l.get("message") == "done"] for host in WORKERS}
all_done = sorted(k for keys in done_lines.values() for k in keys)
check(all_done == sorted(r[0] for r in rows), "each job must be logged done exactly once over the workers")
check(key not in done_lines[cut_host], f"{cut_host} logged the cut job done")
check(key in done_lines[reclaim_host], f"{reclaim_host} did not log the cut job done")
manifest = json.load(open(os.path.join(opts.work, "out", "runs", "rehearsal", "manifest.json")))
manifest_keys = [j["key"] for j in manifest["jobs"]]
check(sorted(manifest_keys) == sorted(r[0] for r in rows) and len(set(manifest_keys)) == jobs,
      "the manifest must list every job exactly once")
check(manifest["dead"] == [], f"dead jobs in the manifest: {manifest['dead']}")
status = subprocess.run(in_namespace("w2", opts.binary, "status", opts.config, "--json"),
                        capture_output=True, text=True, timeout=60)
check(status.returncode == 0 and json.loads(status.stdout.strip().splitlines()[-1])["finished"],
      f"status: {status.returncode} {status.stdout.strip()}")
with open(os.path.join(opts.work, "queue-rows.tsv"), "w") as f:
    f.write("\n".join("\t".join(r) for r in rows) + "\n")

figures = {
    "passed": not problems,
    "jobs": jobs,
    "workers": len(WORKERS),
    "lease_seconds": 3,
    "run_seconds": round(t_end - run_started, 2),
    "jobs_done_per_worker": {h: len(done_lines[h]) for h in WORKERS},
    "cut": {"worker": cut_host, "job": key.split(":")[-1].split("/")[-1]},
    "reclaim_after_cut_seconds": round(t_reclaim - t_cut, 2),
    # Includes waiting for a worker to finish the job it holds: nothing preempts running jobs.
    "reclaim_after_lease_expiry_seconds": round(t_reclaim - t_expiry, 2),
    "cut_worker_attempt_seconds": round(float(discard_line.get("seconds", "nan")), 2),
    "reclaimed_job_done_after_cut_seconds": round(t_done - t_cut, 2),
    "link_down_seconds": round(t_restore - t_cut, 2),
    "fenced_after_link_return_seconds": round(t_discard - t_restore, 2),
    "manifest_jobs": len(manifest_keys),
    "problems": problems,
}
print(json.dumps(figures))
sys.exit(0 if not problems else 1)
