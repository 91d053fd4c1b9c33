#!/usr/bin/env python3
"""csgtile's fit against CGAL's Efficient RANSAC on the same terrestrial gate scan (issue #22
item 4: fitting at >= 2x CGAL, recall not lower).

One run, one machine state: `csgtile synth gate --mode terrestrial` writes the scan (1 M points
by default, 1 cm noise, occlusion by the first hit); then, --repeat times each, in turn:
  - `csgtile fit SCAN --config tests/bench/fit_terrestrial.yaml` with run.threads 1, no
    normals given (it estimates them): the process's wall time, read to write;
  - build/tests/bench/cgal_ransac_bench on the same file, given the exact normal of every
    point (from the truth scene): the time of preprocess() + detect() only.
The best time of each side is kept. Both sides' primitives are scored by member_recall.py
against the truth (volume IoU >= 0.7, one-to-one): csgtile's columns, beams and braces;
CGAL's cylinders as columns (its planes are faces, not members, so CGAL's beams are not
scored). Prints one JSON object with cgal_over_csgtile = CGAL's seconds / csgtile's.

Usage: fit_baseline.py BUILD_DIR WORK_DIR [--points 1000000] [--repeat 3] [--seed 1]
                       [--cgal-epsilon 0.03] [--cgal-cluster-epsilon 0.1]
                       [--cgal-min-points 100] [--cgal-normal-threshold 0.9]
Exit 77 when cgal_ransac_bench was not built (deploy/bench-deps.sh, then re-run cmake).
Standard library only.
"""
import argparse
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def run(cmd, **kw):
    out = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if out.returncode != 0:
        raise RuntimeError("%s failed (%d): %s" % (" ".join(cmd), out.returncode,
                                                   out.stderr.strip()[-2000:]))
    return out.stdout


def recall(truth, fit, las):
    out = run([sys.executable, os.path.join(HERE, "member_recall.py"), "--truth", truth,
               "--fit", fit, "--las", las])
    r = json.loads(out)
    return {"precision": r["precision"], "fitted": r["fitted"],
            "kinds": {k: {"visible": v["visible"], "found": v["found"]}
                      for k, v in r["kinds"].items()}}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build")
    ap.add_argument("work")
    ap.add_argument("--points", type=int, default=1000000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--cgal-epsilon", default="0.03")
    ap.add_argument("--cgal-cluster-epsilon", default="0.1")
    ap.add_argument("--cgal-min-points", default="100")
    ap.add_argument("--cgal-normal-threshold", default="0.9")
    a = ap.parse_args()
    csgtile = os.path.join(a.build, "csgtile")
    cgal = os.path.join(a.build, "tests", "bench", "cgal_ransac_bench")
    if not os.path.exists(cgal):
        print("fit_baseline: %s not built (deploy/bench-deps.sh installs CGAL; re-run cmake)"
              % cgal, file=sys.stderr)
        return 77
    os.makedirs(a.work, exist_ok=True)
    las = os.path.join(a.work, "gate.las")
    truth = os.path.join(a.work, "gate.json")
    run([csgtile, "synth", "gate", "--mode", "terrestrial", "--points", str(a.points),
         "--seed", str(a.seed), "--out", las, "--truth", truth])
    config = os.path.join(a.work, "fit_one_thread.yaml")
    with open(os.path.join(HERE, "fit_terrestrial.yaml")) as f:
        text = f.read()
    with open(config, "w") as f:
        f.write(text.rstrip("\n") + "\nrun:\n  threads: 1\n  seed: %d\n" % a.seed)
    fit = os.path.join(a.work, "fit.json")
    cylinders = os.path.join(a.work, "cgal_cylinders.json")
    ours, theirs, cgal_report = [], [], None
    for _ in range(a.repeat):
        t0 = time.monotonic()
        run([csgtile, "fit", las, "--config", config, "--out", fit])
        ours.append(time.monotonic() - t0)
        r = json.loads(run([cgal, "--las", las, "--truth", truth, "--out", cylinders,
                            "--epsilon", a.cgal_epsilon,
                            "--cluster-epsilon", a.cgal_cluster_epsilon,
                            "--min-points", a.cgal_min_points,
                            "--normal-threshold", a.cgal_normal_threshold,
                            "--seed", str(a.seed)]))
        theirs.append(r["seconds"])
        cgal_report = r
    result = {
        "scan": {"points": a.points, "seed": a.seed, "mode": "terrestrial"},
        "csgtile": {"seconds": min(ours), "all": [round(s, 3) for s in ours],
                    "measured": "process wall, read to write, run.threads 1, no normals given",
                    "recall": recall(truth, fit, las)},
        "cgal": {"seconds": min(theirs), "all": [round(s, 3) for s in theirs],
                 "measured": "preprocess + detect, exact normals given",
                 "report": cgal_report, "recall": recall(truth, cylinders, las)},
    }
    result["cgal_over_csgtile"] = round(min(theirs) / min(ours), 2)
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
