#!/usr/bin/env python3
"""`csgtile fit` end to end: a small terrestrial scan of the gate from `csgtile synth`, fitted
twice with the same seed (byte-identical primitives.json), then matched against the truth by
tests/bench/fit_recall.py (type, radius ±2 cm, axis ±5°, position ±2 cm) with thresholds the
current code meets; and the boxes (beams) matched within ±5 cm, so that the box assembly
cannot lose beams unnoticed while their position is still short of the ±2 cm of the main
match. Also: a missing input and a config with an unknown key exit non-zero with a message
naming the problem.

Usage: fit_synth_recall.py CSGTILE WORKDIR RECALL_SCRIPT MIN_RECALL MIN_PRECISION [MIN_BOXES_5CM
                           [MIN_BEAMS_IOU MIN_IOU_PRECISION]]

The last two are issue #21's measure (tests/bench/member_recall.py beside RECALL_SCRIPT: same
type and volume IoU >= 0.7, one to one): the beams found and the precision.
"""
import json
import os
import shutil
import stat
import subprocess
import sys


def run(*args, check=True):
    p = subprocess.run(list(args), capture_output=True, text=True)
    if check and p.returncode != 0:
        sys.exit("command failed (%d): %s\n%s%s" % (p.returncode, " ".join(args), p.stdout, p.stderr))
    return p


def main():
    bin_, work, recall, min_recall, min_precision = sys.argv[1:6]
    min_boxes = int(sys.argv[6]) if len(sys.argv) > 6 else 0
    min_beams = int(sys.argv[7]) if len(sys.argv) > 7 else 0
    min_iou_precision = float(sys.argv[8]) if len(sys.argv) > 8 else 0.0
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    las, truth = os.path.join(work, "gate.las"), os.path.join(work, "gate.json")
    run(bin_, "synth", "gate", "--mode", "terrestrial", "--points", "400000", "--seed", "3",
        "--out", las, "--truth", truth)
    outs = []
    for k in range(2):
        out = os.path.join(work, "fit%d.json" % k)
        p = run(bin_, "fit", las, "--out", out, "--seed", "5", "--json")
        summary = json.loads(p.stdout)
        if summary["error"] is not None or summary["primitives"] == 0:
            sys.exit("fit found nothing: %s" % p.stdout)
        outs.append(open(out, "rb").read())
    if outs[0] != outs[1]:
        sys.exit("primitives.json differs between two runs with the same seed")
    if b"seconds" in outs[0]:
        sys.exit("primitives.json holds timings")
    print("fit summary:", json.dumps({k: summary[k] for k in ("primitives", "per_type", "unassigned_points", "seconds")}))
    p = run(sys.executable, recall, "--truth", truth, "--fit", os.path.join(work, "fit0.json"),
            "--las", las, "--min-recall", min_recall, "--min-precision", min_precision, check=False)
    print(p.stdout, p.stderr)
    if p.returncode != 0:
        sys.exit("recall below the threshold")
    p = run(sys.executable, recall, "--truth", truth, "--fit", os.path.join(work, "fit0.json"),
            "--las", las, "--position", "0.05")
    boxes = json.loads(p.stdout)["by_type"].get("box", {}).get("matched", 0)
    print("boxes matched within 5 cm:", boxes)
    if boxes < min_boxes:
        sys.exit("boxes matched within 5 cm: %d < %d" % (boxes, min_boxes))
    members = os.path.join(os.path.dirname(recall), "member_recall.py")
    p = run(sys.executable, members, "--truth", truth, "--fit", os.path.join(work, "fit0.json"),
            "--las", las)
    found = json.loads(p.stdout)
    beams = found["kinds"].get("beam", {}).get("found", 0)
    print("by volume IoU >= 0.7: beams %d, precision %.3f" % (beams, found["precision"]))
    if beams < min_beams or found["precision"] < min_iou_precision:
        sys.exit("members by volume IoU: %d beams (min %d), precision %.3f (min %.3f)"
                 % (beams, min_beams, found["precision"], min_iou_precision))

    p = run(bin_, "fit", os.path.join(work, "missing.las"), "--out", os.path.join(work, "x.json"), check=False)
    if p.returncode == 0 or "missing.las" not in p.stderr:
        sys.exit("a missing input must fail naming the file: %d %s" % (p.returncode, p.stderr))
    config = os.path.join(work, "bad.yaml")
    with open(config, "w") as fh:
        fh.write("fit:\n  ransac:\n    epsilom: 0.02\n    min_points: 2\n")
    p = run(bin_, "fit", las, "--config", config, "--out", os.path.join(work, "x.json"), check=False)
    # Every problem at once, each with its key and line; exit 78 (config_invalid).
    if (p.returncode != 78 or "bad.yaml:3: fit.ransac.epsilom" not in p.stderr or
            "bad.yaml:4: fit.ransac.min_points" not in p.stderr):
        sys.exit("config problems must fail naming key and line: %d %s" % (p.returncode, p.stderr))
    # An --out that is not a regular file is refused, never replaced (a device stays one).
    p = run(bin_, "fit", las, "--out", "/dev/null", check=False)
    if p.returncode == 0 or "not a regular file" not in p.stderr or \
            not stat.S_ISCHR(os.stat("/dev/null").st_mode):
        sys.exit("--out /dev/null must be refused and left a device: %d %s"
                 % (p.returncode, p.stderr))
    shutil.rmtree(work, ignore_errors=True)
    print("ok")


if __name__ == "__main__":
    main()
