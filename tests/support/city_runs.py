"""A finished city run for the CLI tests: `csgtile run CONFIG --json`, which must exit 0 with no
dead job; returns its manifest and its tiles.json list. Standard library only."""
import json
import subprocess


def run_city(binary, config, rundir):
    p = subprocess.run([binary, "run", config, "--json"], capture_output=True, text=True)
    assert p.returncode == 0, f"{config}: exit {p.returncode}\n{p.stdout}\n{p.stderr}"
    manifest = json.load(open(f"{rundir}/manifest.json"))
    assert manifest["dead"] == [], manifest["dead"]
    tiles = json.load(open(f"{rundir}/tiles.json"))["tiles"]
    return manifest, tiles
