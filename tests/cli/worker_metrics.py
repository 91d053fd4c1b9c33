#!/usr/bin/env python3
"""`csgtile worker --metrics-listen 127.0.0.1:PORT` on a small SQLite queue: /healthz, /readyz and
/metrics answer while the worker runs; the exposition parses line by line; the queue's jobs by
state and this worker's outcomes count every job; JSON logs of a job carry run and job ids;
timings.json sits beside the manifest; SIGTERM ends the worker with exit 0 and frees the port.
A port in use and a malformed address are clear errors at start-up (exit 74 and 78).
Usage: worker_metrics.py CSGTILE WORKDIR"""
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request

binary, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
subprocess.run([binary, "synth", "gate", "--points", "2000", "--out", f"{work}/scan.las",
                "--truth", f"{work}/truth.json"], check=True, capture_output=True)
scene = json.load(open(f"{work}/truth.json"))
prims = scene["primitives"]
inputs = []
for k in range(4):
    part = dict(scene, name=f"part-{k}", op="fuse", primitives=prims[k * 20:(k + 1) * 20])
    path = f"{work}/part-{k}.json"
    json.dump(part, open(path, "w"))
    inputs.append(path)
config = f"{work}/run.yaml"
with open(config, "w") as f:
    f.write("run:\n  name: scraped\n  inputs:\n" + "".join(f"    - {p}\n" for p in inputs) +
            f"  output: {work}/out\nlog:\n  format: json\n")
subprocess.run([binary, "enqueue", config], check=True, capture_output=True)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def get(port, path):
    """(status, content type, body) of GET http://127.0.0.1:port/path; status 0 if refused."""
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}{path}", timeout=10) as r:
            return r.status, r.headers.get("Content-Type"), r.read().decode()
    except urllib.error.HTTPError as e:
        return e.code, e.headers.get("Content-Type"), e.read().decode()
    except (ConnectionError, urllib.error.URLError):
        return 0, None, ""


SAMPLE = re.compile(r'^([a-zA-Z_:][a-zA-Z0-9_:]*)(\{[a-zA-Z_][a-zA-Z0-9_]*="(?:[^"\\\n]|\\.)*"'
                    r'(?:,[a-zA-Z_][a-zA-Z0-9_]*="(?:[^"\\\n]|\\.)*")*\})? '
                    r'([-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?|\+Inf|-Inf|NaN)$')
COMMENT = re.compile(r'^# (HELP|TYPE) [a-zA-Z_:][a-zA-Z0-9_:]* .+$')


def parse(text):
    assert text.endswith("\n"), "exposition ends with a newline"
    samples = {}
    for n, line in enumerate(text.splitlines(), 1):
        if COMMENT.match(line):
            continue
        m = SAMPLE.match(line)
        assert m, f"line {n} is neither a comment nor a sample: {line!r}"
        samples[m.group(1) + (m.group(2) or "")] = float(m.group(3))
    return samples


port = free_port()
worker = subprocess.Popen([binary, "worker", config, "--metrics-listen", f"127.0.0.1:{port}", "--json"],
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
try:
    # Wait for the endpoint (the worker starts it before opening the queue).
    deadline = time.time() + 60
    while get(port, "/healthz")[0] == 0:
        assert worker.poll() is None, worker.communicate()
        assert time.time() < deadline, "the endpoint never answered"
        time.sleep(0.05)
    status, ctype, body = get(port, "/healthz")
    assert status == 200 and json.loads(body)["status"] == "ok", (status, body)
    # Scrape until every job is done (the worker keeps running: no --exit-when-idle).
    scrapes = 0
    while True:
        status, ctype, body = get(port, "/metrics")
        assert status == 200, (status, body)
        assert ctype == "text/plain; version=0.0.4; charset=utf-8", ctype
        samples = parse(body)
        scrapes += 1
        if samples.get('csgtile_queue_jobs{state="done"}') == 4 and \
                samples.get('csgtile_worker_jobs_total{outcome="done"}') == 4:
            break
        assert worker.poll() is None, worker.communicate()
        assert time.time() < deadline + 240, samples
        time.sleep(0.1)
    for state in ("queued", "running", "retry", "dead"):
        assert samples[f'csgtile_queue_jobs{{state="{state}"}}'] == 0, (state, samples)
    assert samples["csgtile_queue_up"] == 1
    assert samples['csgtile_worker_jobs_total{outcome="dead"}'] == 0
    assert samples["csgtile_worker_job_duration_seconds_count"] == 4
    assert samples['csgtile_worker_job_duration_seconds_bucket{le="+Inf"}'] == 4
    assert samples["csgtile_primitives_built_total"] == 80, samples["csgtile_primitives_built_total"]
    assert samples["csgtile_published_bytes_total"] > 0
    for stage in ("read", "build", "check", "boolean", "publish"):
        assert f'csgtile_worker_stage_seconds_total{{stage="{stage}"}}' in samples, stage
    assert any(k.startswith("csgtile_build_info{version=") for k in samples)
    assert samples["csgtile_worker_draining"] == 0
    # Wait for the publish that follows the last job, then readiness and liveness hold.
    manifest_path = f"{work}/out/runs/scraped/manifest.json"
    while not os.path.exists(manifest_path):
        assert worker.poll() is None and time.time() < deadline + 240
        time.sleep(0.1)
    status, _, body = get(port, "/readyz")
    assert status == 200 and json.loads(body) == {"status": "ready", "draining": False, "queue": "ok"}, body
    assert get(port, "/healthz")[0] == 200
    assert get(port, "/nothing")[0] == 404
finally:
    worker.send_signal(signal.SIGTERM)
    out, err = worker.communicate(timeout=120)
assert worker.returncode == 0, (worker.returncode, out, err)
assert get(port, "/healthz")[0] == 0, "the endpoint stops with the worker"
logs = [json.loads(line) for line in err.splitlines() if line.startswith("{")]
listening = [l for l in logs if l.get("component") == "metrics" and l.get("message") == "listening"]
assert listening and listening[0]["address"] == f"127.0.0.1:{port}", listening
done = [l for l in logs if l.get("component") == "job" and l.get("message") == "done"]
assert len(done) == 4 and all(l["run"] == "scraped" and l["job"].startswith("build:scraped:")
                              and l["attempt"] == 1 for l in done), done
manifest = json.load(open(manifest_path))
assert manifest["timings"] == "timings.json" and all("timings" not in j["result"] for j in manifest["jobs"])
timings = json.load(open(f"{work}/out/runs/scraped/timings.json"))
assert [j["key"] for j in timings["jobs"]] == [j["key"] for j in manifest["jobs"]]
assert all(set(j["stages"]) - {"fetch"} == {"read", "build", "check", "boolean", "publish"}
           for j in timings["jobs"]), timings

# A port in use: exit 74 (io) naming the address; a malformed address: exit 78 naming the flag.
with socket.socket() as holder:
    holder.bind(("127.0.0.1", 0))
    holder.listen()
    busy = holder.getsockname()[1]
    p = subprocess.run([binary, "worker", config, "--exit-when-idle", "--metrics-listen", f"127.0.0.1:{busy}"],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 74, (p.returncode, p.stderr)
    assert f"127.0.0.1:{busy}" in p.stderr and "Address already in use" in p.stderr, p.stderr
p = subprocess.run([binary, "worker", config, "--exit-when-idle", "--metrics-listen", "db.example:9464"],
                   capture_output=True, text=True, timeout=60)
assert p.returncode == 78 and "--metrics-listen" in p.stderr and "db.example:9464" in p.stderr, (p.returncode, p.stderr)
# The config key works the same (environment override here); `off` turns it off.
env = dict(os.environ, CSGTILE_METRICS__LISTEN="127.0.0.1:99999")
p = subprocess.run([binary, "run", config], capture_output=True, text=True, timeout=120, env=env)
assert p.returncode == 78 and "metrics.listen" in p.stderr, (p.returncode, p.stderr)
p = subprocess.run([binary, "run", config, "--metrics-listen", "off"], capture_output=True, text=True,
                   timeout=120, env=env)
assert p.returncode == 0, (p.returncode, p.stderr)
print(f"ok: 4 jobs scraped over {scrapes} scrape(s) on port {port}")
