#!/usr/bin/env python3
"""`csgtile run` over inputs named by URL, against real loopback servers: the fault-injecting
HTTP server of tests/support and (when installed) @20minutes/s3rver, which checks SigV4
signatures. The S3 objects are uploaded by this script with its own SigV4 signer (Python's
hmac/hashlib), an implementation independent of csgtile's.

Checks: good inputs (plain, flaky-then-ok, redirected, file://, s3://, with and without a
#sha256 fragment) are done and their input_sha256 in the manifest is the content's; bad ones
(404, a forbidden scheme, a redirect to a link-local address, a wrong checksum, an oversized
body, a wrong S3 secret) end dead with a reason naming the cause, without stopping the run;
a second run of the same config publishes byte-identical manifests.
Usage: run_fetch_inputs.py CSGTILE SOURCE_DIR WORKDIR [S3RVER_DIR]"""
import datetime
import hashlib
import hmac
import json
import os
import shutil
import subprocess
import sys
import urllib.parse
import urllib.request

binary, source, work = sys.argv[1], sys.argv[2], sys.argv[3]
s3rver_dir = os.environ.get("CSGTILE_S3RVER_DIR", sys.argv[4] if len(sys.argv) > 4 else "")
require_s3 = os.environ.get("CSGTILE_REQUIRE_S3RVER") == "1"
shutil.rmtree(work, ignore_errors=True)
os.makedirs(f"{work}/served")
scenes = f"{source}/config/examples/scenes"
for name in ("pavilion.json", "courtyard_block.json"):
    shutil.copy(f"{scenes}/{name}", f"{work}/served/{name}")
sha = {n: hashlib.sha256(open(f"{scenes}/{n}", "rb").read()).hexdigest()
       for n in ("pavilion.json", "courtyard_block.json")}

servers = []


def start(cmd):
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, start_new_session=True)
    servers.append(p)
    line = p.stdout.readline().strip()
    assert line.isdigit(), (cmd, line)
    return int(line)


def sigv4_put(port, bucket, key, body, access, secret, region="us-east-1"):
    """Signs and sends an S3 PUT (AWS Signature V4), written from AWS's documentation."""
    host = f"127.0.0.1:{port}"
    path = "/" + bucket + "/" + urllib.parse.quote(key, safe="/~")
    now = datetime.datetime.now(datetime.timezone.utc)
    amz_date, day = now.strftime("%Y%m%dT%H%M%SZ"), now.strftime("%Y%m%d")
    payload = hashlib.sha256(body).hexdigest()
    headers = {"host": host, "x-amz-content-sha256": payload, "x-amz-date": amz_date}
    signed = ";".join(sorted(headers))
    canonical = "\n".join(["PUT", path, ""] + [f"{k}:{headers[k]}" for k in sorted(headers)] +
                          ["", signed, payload])
    scope = f"{day}/{region}/s3/aws4_request"
    to_sign = "\n".join(["AWS4-HMAC-SHA256", amz_date, scope,
                         hashlib.sha256(canonical.encode()).hexdigest()])
    k = ("AWS4" + secret).encode()
    for part in (day, region, "s3", "aws4_request"):
        k = hmac.new(k, part.encode(), hashlib.sha256).digest()
    signature = hmac.new(k, to_sign.encode(), hashlib.sha256).hexdigest()
    request = urllib.request.Request(f"http://{host}{path}", data=body, method="PUT")
    for name, value in headers.items():
        if name != "host":
            request.add_header(name, value)
    request.add_header("Authorization", f"AWS4-HMAC-SHA256 Credential={access}/{scope}, "
                                        f"SignedHeaders={signed}, Signature={signature}")
    with urllib.request.urlopen(request) as response:
        assert response.status == 200, response.status


try:
    http = start(["python3", f"{source}/tests/support/fault_http_server.py", f"{work}/served"])
    base = f"http://127.0.0.1:{http}"
    good = {
        f"{base}/ok/pavilion.json#sha256={sha['pavilion.json']}": sha["pavilion.json"],
        f"{base}/flaky/2/courtyard_block.json": sha["courtyard_block.json"],
        f"{base}/redirect/2/pavilion.json": sha["pavilion.json"],
        f"file://{work}/served/courtyard_block.json": sha["courtyard_block.json"],
    }
    bad = {
        f"{base}/status/404": "HTTP 404",
        "gopher://127.0.0.1/pavilion.json": "scheme 'gopher' is not allowed",
        f"{base}/to/http%3A%2F%2F169.254.169.254%2Flatest%2Fmeta-data": "169.254.169.254",
        f"{base}/ok/courtyard_block.json#sha256={'0' * 64}": "does not match",
        f"{base}/endless": "size cap",
    }
    s3_endpoint = ""
    if s3rver_dir and os.path.exists(f"{s3rver_dir}/package.json"):
        os.makedirs(f"{work}/s3")
        s3 = start(["node", f"{source}/tests/support/s3_server.cjs", s3rver_dir, f"{work}/s3", "tiles"])
        s3_endpoint = f"http://127.0.0.1:{s3}"
        sigv4_put(s3, "tiles", "city/pavilion.json", open(f"{scenes}/pavilion.json", "rb").read(),
                  "S3RVER", "S3RVER")
        good["s3://tiles/city/pavilion.json"] = sha["pavilion.json"]
        bad["s3://tiles/city/missing.json"] = "HTTP 404"
    elif require_s3:
        sys.exit(f"@20minutes/s3rver not found at {s3rver_dir!r}")
    else:
        print("note: @20minutes/s3rver not installed; the s3:// inputs are left out")

    config = f"{work}/run.yaml"
    with open(config, "w") as f:
        f.write("run:\n  name: fetched\n  inputs:\n" +
                "".join(f"    - {json.dumps(u)}\n" for u in list(good) + list(bad)) +
                f"  output: {work}/out\nqueue:\n  max_attempts: 2\nlog:\n  format: json\n"
                f"fetch:\n  schemes: [file, http, https, s3]\n  max_bytes: 1000000\n"
                f"  s3_endpoint: \"{s3_endpoint}\"\n")
    env = dict(os.environ, AWS_ACCESS_KEY_ID="S3RVER", AWS_SECRET_ACCESS_KEY="S3RVER")
    manifests = []
    for attempt in range(2):
        p = subprocess.run([binary, "run", config, "--json"], capture_output=True, text=True,
                           env=env, timeout=600)
        assert p.returncode == 3, (p.returncode, p.stdout[-2000:], p.stderr[-4000:])  # jobs_failed
        assert "S3RVER" not in p.stderr.replace('"S3RVER"', ""), "no secret in logs"
        manifest_path = f"{work}/out/runs/fetched/manifest.json"
        manifests.append(open(manifest_path, "rb").read())
        manifest = json.loads(manifests[-1])
        by_input = {job["result"]["input"]: job["result"] for job in manifest["jobs"]}
        for url, digest in good.items():
            assert url in by_input, (url, sorted(by_input))
            assert by_input[url]["input_sha256"] == digest, (url, by_input[url])
        dead = {d["key"].split(":", 2)[2]: d for d in manifest["dead"]}
        assert set(dead) == set(bad), (sorted(dead), sorted(bad))
        for url, cause in bad.items():
            assert cause in dead[url]["error"], (url, dead[url])
        if attempt == 0:
            shutil.rmtree(f"{work}/out/runs")
            os.remove(f"{work}/out/queue.sqlite")
    assert manifests[0] == manifests[1], "a second run publishes the same manifest"

    # A wrong S3 secret: the job ends dead with the server's 403; the secret is not logged.
    if s3_endpoint:
        with open(config) as f:
            text = f.read()
        with open(f"{work}/s3-only.yaml", "w") as f:
            f.write(text.replace("name: fetched", "name: wrong-secret").split("  output:")[0]
                    .split("  inputs:")[0] + "  inputs:\n    - s3://tiles/city/pavilion.json\n" +
                    "  output:" + text.split("  output:")[1])
        env_bad = dict(env, AWS_SECRET_ACCESS_KEY="not-the-secret")
        p = subprocess.run([binary, "run", f"{work}/s3-only.yaml", "--json"], capture_output=True,
                           text=True, env=env_bad, timeout=300)
        assert p.returncode == 3, (p.returncode, p.stdout, p.stderr[-3000:])
        assert "not-the-secret" not in p.stdout + p.stderr
        m = json.load(open(f"{work}/out/runs/wrong-secret/manifest.json"))
        assert len(m["dead"]) == 1 and "HTTP 403" in m["dead"][0]["error"], m["dead"]
    print(f"ok: {len(good)} fetched inputs done, {len(bad)} bad inputs dead with their reasons")
finally:
    for s in servers:
        s.terminate()
        s.wait()
