#!/usr/bin/env python3
"""Checks the Kubernetes manifests without a cluster:
  1. yamllint (deploy/k8s/.yamllint) on the sources;
  2. `kubectl kustomize` of each kustomization (overlays/dev, overlays/prod, indexed-job);
  3. what the rendered objects must hold: probes on the health endpoint's port, Prometheus
     annotations, non-root and read-only root file system with a writable /tmp, references to
     Secrets, ConfigMaps and claims that exist (or are documented as created by hand), the
     grace period equal to the systemd unit's TimeoutStopSec (one drain everywhere), the
     Indexed Job's completions equal to its inputs;
  4. each csgtile.yaml in a rendered ConfigMap through `csgtile validate-config`, with the
     containers' literal environment (CSGTILE_* overrides) applied;
  5. `kubectl apply --dry-run=client` of each rendering when a cluster answers; kubectl needs
     the API server's discovery even for a client-side dry run (also with --validate=false),
     so without a cluster this step is skipped with a message.
Usage: check-manifests.py [CSGTILE]   exit 0 ok, 1 problems, 77 yamllint or kubectl missing."""
import os
import re
import shutil
import subprocess
import sys
import tempfile

import yaml

here = os.path.dirname(os.path.abspath(__file__))
repo = os.path.dirname(os.path.dirname(here))
binary = sys.argv[1] if len(sys.argv) > 1 else os.path.join(repo, "build", "csgtile")
KUSTOMIZATIONS = ["overlays/dev", "overlays/prod", "indexed-job"]
# Created by hand before `kubectl apply -k overlays/prod` (its kustomization says how).
EXTERNAL_SECRETS = {"overlays/prod": {"csgtile-postgres", "csgtile-db-ca"}}
METRICS_PORT = 9464
problems = []


def problem(where, message):
    problems.append(f"{where}: {message}")
    print(f"FAIL {where}: {message}")


for tool in ("yamllint", "kubectl"):
    if shutil.which(tool) is None:
        print(f"SKIP: {tool} is not installed (deploy/setup.sh installs yamllint; kubectl comes "
              "with your Kubernetes tools)")
        sys.exit(77)

# 1. yamllint
lint = subprocess.run(["yamllint", "-s", "-c", os.path.join(here, ".yamllint"), here],
                      capture_output=True, text=True)
if lint.returncode != 0:
    problem("yamllint", lint.stdout + lint.stderr)
else:
    print("ok yamllint")


def timeout_stop_sec():
    unit = open(os.path.join(repo, "deploy", "systemd", "csgtile-worker.service")).read()
    match = re.search(r"^TimeoutStopSec=(\d+)s?$", unit, re.M)
    return int(match.group(1)) if match else None


def pod_specs(obj):
    kind = obj["kind"]
    if kind == "StatefulSet":
        return [dict(obj["spec"]["template"],
                     volumeClaimTemplates=obj["spec"].get("volumeClaimTemplates", []))]
    if kind in ("Deployment", "Job"):
        return [obj["spec"]["template"]]
    if kind == "CronJob":
        return [obj["spec"]["jobTemplate"]["spec"]["template"]]
    return []


def check_pod(where, template, names, external, workload):
    spec = template["spec"]
    pod_security = spec.get("securityContext", {})
    if not pod_security.get("runAsNonRoot"):
        problem(where, "pod securityContext.runAsNonRoot is not true")
    if spec.get("automountServiceAccountToken") is not False:
        problem(where, "automountServiceAccountToken should be false (no API access needed)")
    volumes = {v["name"]: v for v in spec.get("volumes", [])}
    claims = {t["metadata"]["name"] for t in template.get("volumeClaimTemplates", [])}
    for v in volumes.values():
        if "configMap" in v and v["configMap"]["name"] not in names["ConfigMap"]:
            problem(where, f"volume {v['name']}: no ConfigMap {v['configMap']['name']}")
        if "secret" in v and v["secret"]["secretName"] not in names["Secret"] | external:
            problem(where, f"volume {v['name']}: no Secret {v['secret']['secretName']}")
        if "persistentVolumeClaim" in v and \
                v["persistentVolumeClaim"]["claimName"] not in names["PersistentVolumeClaim"]:
            problem(where, f"volume {v['name']}: no claim {v['persistentVolumeClaim']['claimName']}")
    for c in spec["containers"]:
        cwhere = f"{where}/{c['name']}"
        security = c.get("securityContext", {})
        if security.get("allowPrivilegeEscalation") is not False:
            problem(cwhere, "allowPrivilegeEscalation should be false")
        if "ALL" not in security.get("capabilities", {}).get("drop", []):
            problem(cwhere, "capabilities should drop ALL")
        resources = c.get("resources", {})
        if "memory" not in resources.get("requests", {}) or "memory" not in resources.get("limits", {}):
            problem(cwhere, "memory request and limit must be set")
        for mount in c.get("volumeMounts", []):
            if mount["name"] not in volumes and mount["name"] not in claims:
                problem(cwhere, f"mount of unknown volume {mount['name']}")
        for env in c.get("env", []):
            ref = env.get("valueFrom", {}).get("secretKeyRef")
            if ref and ref["name"] not in names["Secret"] | external:
                problem(cwhere, f"env {env['name']}: no Secret {ref['name']}")
        if not workload:
            continue
        # csgtile containers: the image set by the overlay, read-only root, writable /tmp.
        if c["image"] == "csgtile":
            problem(cwhere, "image placeholder 'csgtile' not replaced (kustomize images:)")
        if not security.get("readOnlyRootFilesystem"):
            problem(cwhere, "readOnlyRootFilesystem should be true")
        scratch = [m for m in c.get("volumeMounts", []) if m["mountPath"] == "/tmp"]
        if c["args"][0] in ("worker", "run") and \
                not (scratch and "emptyDir" in volumes[scratch[0]["name"]]):
            problem(cwhere, "/tmp should be an emptyDir (the root file system is read-only)")


def check_worker(where, deployment):
    template = deployment["spec"]["template"]
    spec = template["spec"]
    container = spec["containers"][0]
    ports = {p["name"]: p["containerPort"] for p in container.get("ports", [])}
    if ports.get("metrics") != METRICS_PORT:
        problem(where, f"container port 'metrics' should be {METRICS_PORT}: {ports}")
    expected = {"livenessProbe": "/healthz", "readinessProbe": "/readyz", "startupProbe": "/healthz"}
    for probe, path in expected.items():
        get = container.get(probe, {}).get("httpGet", {})
        if get.get("path") != path or get.get("port") not in ("metrics", METRICS_PORT):
            problem(where, f"{probe} should GET {path} on the metrics port: {get}")
    annotations = template["metadata"].get("annotations", {})
    if annotations.get("prometheus.io/scrape") != "true" or \
            annotations.get("prometheus.io/port") != str(METRICS_PORT) or \
            annotations.get("prometheus.io/path") != "/metrics":
        problem(where, f"Prometheus annotations: {annotations}")
    listen = {e["name"]: e.get("value") for e in container.get("env", [])}.get("CSGTILE_METRICS__LISTEN")
    if listen != f"0.0.0.0:{METRICS_PORT}":
        problem(where, "CSGTILE_METRICS__LISTEN should be 0.0.0.0:9464 (probes come from the kubelet)")
    grace = spec.get("terminationGracePeriodSeconds")
    stop = timeout_stop_sec()
    if grace is None or stop is None or grace != stop:
        problem(where, f"terminationGracePeriodSeconds {grace} should equal the systemd unit's "
                       f"TimeoutStopSec {stop} (one drain budget)")
    if container["args"][0] != "worker":
        problem(where, f"worker args: {container['args']}")


def validate_configs(where, objects, names):
    """Each csgtile.yaml of a ConfigMap through `csgtile validate-config`, with the literal
    CSGTILE_* environment of the containers that mount it."""
    if not os.access(binary, os.X_OK):
        print(f"SKIP {where}: csgtile validate-config (no binary at {binary})")
        return
    known = subprocess.run([binary, "config", "schema"], capture_output=True, text=True).stdout
    for cm in (o for o in objects if o["kind"] == "ConfigMap" and "csgtile.yaml" in o.get("data", {})):
        env = {}
        for obj in objects:
            for template in pod_specs(obj):
                spec = template["spec"]
                if not any(v.get("configMap", {}).get("name") == cm["metadata"]["name"]
                           for v in spec.get("volumes", [])):
                    continue
                for c in spec["containers"]:
                    for e in c.get("env", []):
                        # Config overrides are CSGTILE_<SECTION>__<KEY> (CSGTILE_PG_PASSWORD is not).
                        if not e["name"].startswith("CSGTILE_") or "__" not in e["name"]:
                            continue
                        section = e["name"][len("CSGTILE_"):].split("__")[0].lower()
                        if f'"{section}"' not in known:
                            print(f"NOTE {where}: {e['name']} not checked: this csgtile has no "
                                  f"'{section}' section")
                            continue
                        # Secret values are not known here: a stand-in of the right type.
                        env[e["name"]] = e.get("value", "host=db.example dbname=csgtile")
        with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
            f.write(cm["data"]["csgtile.yaml"])
        clean = {k: v for k, v in os.environ.items() if not k.startswith("CSGTILE_")}
        result = subprocess.run([binary, "validate-config", "--no-input-check", f.name], capture_output=True, text=True,
                                env={**clean, **env})
        os.unlink(f.name)
        if result.returncode != 0:
            problem(f"{where}/{cm['metadata']['name']}",
                    f"csgtile validate-config (env {sorted(env)}): {result.stdout}{result.stderr}")
        else:
            print(f"ok {where}: {cm['metadata']['name']} csgtile.yaml valid (env {sorted(env)})")


cluster = subprocess.run(["kubectl", "version", "--request-timeout=5s", "-o", "json"],
                         capture_output=True, text=True).returncode == 0
for kustomization in KUSTOMIZATIONS:
    where = kustomization
    rendered = subprocess.run(["kubectl", "kustomize", os.path.join(here, kustomization)],
                              capture_output=True, text=True)
    if rendered.returncode != 0:
        problem(where, "kubectl kustomize: " + rendered.stderr.strip())
        continue
    objects = [o for o in yaml.safe_load_all(rendered.stdout) if o]
    print(f"ok {where}: kubectl kustomize, {len(objects)} objects "
          f"({', '.join(sorted(o['kind'] for o in objects))})")
    lint = subprocess.run(["yamllint", "-s", "-d", "{extends: relaxed, rules: {line-length: disable}}", "-"],
                          input=rendered.stdout, capture_output=True, text=True)
    if lint.returncode != 0:
        problem(where, "yamllint of the rendering: " + lint.stdout)
    names = {k: {o["metadata"]["name"] for o in objects if o["kind"] == k}
             for k in ("ConfigMap", "Secret", "PersistentVolumeClaim")}
    external = EXTERNAL_SECRETS.get(kustomization, set())
    for obj in objects:
        owhere = f"{where}:{obj['kind']}/{obj['metadata']['name']}"
        if obj["kind"] not in ("Namespace",) and "namespace" not in obj["metadata"]:
            problem(owhere, "no namespace set by the kustomization")
        for template in pod_specs(obj):
            check_pod(owhere, template, names, external,
                      workload=obj["metadata"]["name"].startswith("csgtile-")
                      and obj["kind"] != "StatefulSet")
        if obj["kind"] == "Deployment" and obj["metadata"]["name"] == "csgtile-worker":
            check_worker(owhere, obj)
        if obj["kind"] == "CronJob":
            args = obj["spec"]["jobTemplate"]["spec"]["template"]["spec"]["containers"][0]["args"]
            if args[0] != "enqueue":
                problem(owhere, f"the CronJob should run csgtile enqueue: {args}")
        if obj["kind"] == "Job" and obj["spec"].get("completionMode") == "Indexed":
            cm_name = next(v["configMap"]["name"] for v in obj["spec"]["template"]["spec"]["volumes"]
                           if "configMap" in v)
            cm = next(o for o in objects if o["kind"] == "ConfigMap" and o["metadata"]["name"] == cm_name)
            inputs = yaml.safe_load(cm["data"]["csgtile.yaml"])["run"]["inputs"]
            if obj["spec"]["completions"] != len(inputs):
                problem(owhere, f"completions {obj['spec']['completions']} != {len(inputs)} inputs")
    if not any(o["kind"] == "Deployment" for o in objects) and kustomization.startswith("overlays"):
        problem(where, "no worker Deployment")
    validate_configs(where, objects, names)
    if cluster:
        dry = subprocess.run(["kubectl", "apply", "--dry-run=client", "-f", "-"], input=rendered.stdout,
                             capture_output=True, text=True)
        if dry.returncode != 0:
            problem(where, "kubectl apply --dry-run=client: " + dry.stderr)
        else:
            print(f"ok {where}: kubectl apply --dry-run=client")
if not cluster:
    print("SKIP kubectl apply --dry-run=client: no cluster answers (kubectl needs the API server's "
          "discovery even for a client-side dry run, with or without --validate=false)")

print(f"{len(problems)} problem(s)" if problems else "all manifest checks passed")
sys.exit(1 if problems else 0)
