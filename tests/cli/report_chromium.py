#!/usr/bin/env python3
"""The run report (issue #9 item 6) opened in headless Chromium: `csgtile run` publishes the
README's demo scenes placed in RD New (tiles/model.glb, as run_demo_tiles.sh), report_sample
writes a report for its GLBs (plus a cell whose GLB is missing), twice with the same bytes
but for timings.js, and report_chromium.cjs (puppeteer-core) opens report/index.html from
file://: no console error, no failed or remote request, the 3D canvas not blank in a
screenshot, orbiting changes it. When the run itself wrote report/index.html, that page is
checked the same way.

Usage: report_chromium.py CSGTILE REPORT_SAMPLE SOURCE_DIR WORKDIR PUPPETEER_CORE_DIR
  $CSGTILE_CHROMIUM overrides the browser (default: chromium on the PATH, /usr/bin/chromium),
  $CSGTILE_PUPPETEER_DIR the npm package puppeteer-core (deploy/run-tests.sh installs it).
Exit 77 (skipped) when chromium, node or puppeteer-core is missing, or csgtile was built
without its 3D viewer (three and esbuild from npm at configure time), unless
CSGTILE_REQUIRE_REPORT_VIEWER=1: then each of those fails the test."""
import json
import os
import shutil
import subprocess
import sys

binary, sample, source, work, puppeteer = sys.argv[1:6]
puppeteer = os.environ.get("CSGTILE_PUPPETEER_DIR", puppeteer)
chromium = os.environ.get("CSGTILE_CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
required = os.environ.get("CSGTILE_REQUIRE_REPORT_VIEWER") == "1"


def skip(reason):
    print(f"report_chromium: {reason}")
    if required:
        print("CSGTILE_REQUIRE_REPORT_VIEWER=1: failing instead of skipping")
        sys.exit(1)
    print("skipped (deploy/setup.sh installs chromium, deploy/run-tests.sh the npm packages)")
    sys.exit(77)


if not shutil.which("node"):
    skip("node not found")
if not os.access(chromium, os.X_OK):
    skip(f"chromium not found ({chromium}; set CSGTILE_CHROMIUM)")
if not os.path.isfile(os.path.join(puppeteer, "package.json")):
    skip(f"puppeteer-core not found ({puppeteer}; set CSGTILE_PUPPETEER_DIR)")

shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)

# The demo scenes placed in RD New + NAP: the run then writes tiles/model.glb.
inputs = []
for scene in ("pavilion", "courtyard_block", "pavilion_fused"):
    text = open(f"{source}/config/examples/scenes/{scene}.json").read()
    assert text.startswith("{"), scene
    placed = f"{work}/{scene}.json"
    with open(placed, "w") as f:
        f.write('{"crs":"EPSG:28992+5709","origin":[155000,463000,1.25],' + text[1:])
    inputs.append(placed)
env = dict(os.environ, CSGTILE_RUN__OUTPUT=f"{work}/out", CSGTILE_RUN__INPUTS=",".join(inputs),
           CSGTILE_LOG__LEVEL="error")
p = subprocess.run([binary, "run", f"{source}/config/examples/demo.yaml"], env=env,
                   capture_output=True, text=True, timeout=600)
assert p.returncode == 0, (p.returncode, p.stdout, p.stderr[-3000:])
run_dir = f"{work}/out/runs/demo"
# tiles/model.glb today; any GLB the run wrote under tiles/ (one report cell each).
glbs = sorted(os.path.join(d, f) for d, _, files in os.walk(f"{run_dir}/tiles")
              for f in files if f.endswith(".glb"))
assert glbs, "the run wrote no GLB under tiles/"

# The same input twice: the same bytes in every file but timings.js.
keys = {}
for name in ("sample", "again"):
    p = subprocess.run([sample, f"{work}/{name}", *glbs], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, (p.returncode, p.stdout, p.stderr)
    keys[name] = [line for line in p.stdout.splitlines() if not line.endswith("(not deterministic)")]
assert keys["sample"] == keys["again"] and "report/index.html" in keys["sample"], keys
for key in keys["sample"]:
    a = open(f"{work}/sample/{key}", "rb").read()
    b = open(f"{work}/again/{key}", "rb").read()
    assert a == b, f"{key} differs between two reports of the same input"
print(f"report_sample: {len(keys['sample'])} deterministic files, identical twice")

pages = [f"{work}/sample/report/index.html"]
if os.path.isfile(f"{run_dir}/report/index.html"):
    pages.append(f"{run_dir}/report/index.html")

failed = False
for number, page in enumerate(pages):
    html = open(page, encoding="utf-8").read()
    if 'data-viewer="unavailable"' in html and "built without its viewer library" in html:
        skip(f"{page}: csgtile was built without its 3D viewer (configure with three and "
             "esbuild in <build>/npm/node_modules, or set CSGTILE_REPORT_NPM_DIR)")
    shot = f"{work}/report_{number}.png"
    p = subprocess.run(["node", f"{source}/tests/cli/report_chromium.cjs", puppeteer, chromium,
                        os.path.abspath(page), shot], capture_output=True, text=True, timeout=300)
    print(f"{page}:")
    print(p.stdout.strip() or p.stderr[-3000:])
    if p.returncode != 0:
        failed = True
        if p.stderr:
            print(p.stderr[-3000:])
    else:
        print(f"ok: rendered offline, screenshot {shot}")
sys.exit(1 if failed else 0)
