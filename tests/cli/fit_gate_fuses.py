#!/usr/bin/env python3
"""Issue #20's fitted gate: `csgtile synth gate` scanned from the ground (1 M points, seeds 1-3),
fitted with tests/bench/fit_terrestrial.yaml and assembled in the fuzz mode a city run uses
(`--snap-distance 0.005 --snap-angle 0.5`, the city.snap_* defaults). Each scan's model must have
every object fused (no problem 'not fused', objects_failed 0) and be valid by the checker
(`csgtile inspect --json`), and its volume must lie within MAX_VOLUME_ERROR of the true
primitives' union (the truth scene assembled the same way).

The issue's aim is one solid within 1 % of the union. Measured 2026-12-06: seeds 1/2/3 fuse into
21/26/37 objects (the fitted members that stop short of the frame stay apart), volumes -4.9 %,
-1.1 %, -14.5 % (missed beams and extra boxes: issue #21). The volume bound guards against a
giant primitive or a lost object, not the aim.

Usage: fit_gate_fuses.py CSGTILE WORKDIR FIT_CONFIG MAX_VOLUME_ERROR
"""
import json
import os
import shutil
import subprocess
import sys


def run(*args):
    p = subprocess.run(list(args), capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit("command failed (%d): %s\n%s%s" % (p.returncode, " ".join(args), p.stdout, p.stderr))
    return p.stdout


def assemble(bin_, scene, out):
    stdout = run(bin_, "assemble", scene, "--out", out, "--snap-distance", "0.005",
                 "--snap-angle", "0.5", "--json")
    return json.loads(stdout)


def main():
    bin_, work, config, max_error = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    failures = []
    for seed in (1, 2, 3):
        las = os.path.join(work, "gate%d.las" % seed)
        truth = os.path.join(work, "gate%d.json" % seed)
        fit = os.path.join(work, "fit%d.json" % seed)
        run(bin_, "synth", "gate", "--mode", "terrestrial", "--points", "1000000", "--seed",
            str(seed), "--out", las, "--truth", truth)
        run(bin_, "fit", las, "--config", config, "--seed", "1", "--out", fit)
        true_union = assemble(bin_, truth, os.path.join(work, "truth%d" % seed))
        fused = assemble(bin_, fit, os.path.join(work, "model%d" % seed))
        stats = fused["statistics"]
        not_fused = [p for p in fused.get("problems", []) if "not fused" in json.dumps(p)]
        inspect = json.loads(run(bin_, "inspect", fused["model"], "--json"))
        error = fused["total_volume"] / true_union["total_volume"] - 1.0
        print("seed %d: %d primitives -> %d objects (%d failed), valid %s, volume %.3f m3, "
              "true union %.3f m3 (%+.1f %%)" % (seed, stats["primitives"], stats["objects"],
                                                 stats["objects_failed"], inspect["valid"],
                                                 fused["total_volume"], true_union["total_volume"],
                                                 100 * error))
        if stats["objects_failed"] != 0 or not_fused:
            failures.append("seed %d: objects not fused: %s" % (seed, not_fused))
        if inspect["valid"] is not True:
            failures.append("seed %d: the fused model is not valid" % seed)
        if abs(error) > max_error:
            failures.append("seed %d: volume %+.1f %% off the true union (bound %.0f %%)"
                            % (seed, 100 * error, 100 * max_error))
    if failures:
        sys.exit("\n".join(failures))


if __name__ == "__main__":
    main()
