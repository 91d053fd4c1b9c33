"""Shared by the city-run tests that write their own LAS (city_run_dome.py,
city_run_houses.py): a classified scan seen from the air, a LAS writer, a city run of it, its
CityJSONSeq's objects and their val3dity check. Standard library only."""
import glob
import json
import math
import os
import struct
import subprocess


def seen_from_above(rnd, x0, y0, width, depth, roof, density=10.0, sigma=0.02):
    """Points over [x0, x0 + width] x [y0, y0 + depth] at `density` per m² (a jittered grid,
    noise `sigma`, drawn from `rnd`) as (x, y, z, class): a building point (class 6) at
    roof(x, y) where it is not None, else the ground (class 2) at z = 0."""
    step = 1 / math.sqrt(density)
    out = []
    for i in range(int(width / step)):
        for j in range(int(depth / step)):
            x = x0 + (i + rnd.random()) * step
            y = y0 + (j + rnd.random()) * step
            z = roof(x, y)
            out.append((x, y, (z if z is not None else 0.0) + rnd.gauss(0, sigma),
                        6 if z is not None else 2))
    return out


def write_las(path, points, tag):
    """LAS 1.2, point format 0, scale 1 mm; `points` as (x, y, z, class); `tag` names the
    generating software."""
    scale = 0.001
    xs, ys, zs = ([p[k] for p in points] for k in range(3))
    offset = (math.floor(min(xs)), math.floor(min(ys)), 0.0)
    header = bytearray(227)
    header[0:4] = b"LASF"
    struct.pack_into("<BB", header, 24, 1, 2)
    header[26:58] = tag.encode()[:32].ljust(32, b"\0")
    struct.pack_into("<HHH", header, 90, 1, 2026, 227)
    struct.pack_into("<IIBHI", header, 96, 227, 0, 0, 20, len(points))
    struct.pack_into("<5I", header, 111, len(points), 0, 0, 0, 0)
    struct.pack_into("<3d", header, 131, scale, scale, scale)
    struct.pack_into("<3d", header, 155, *offset)
    struct.pack_into("<6d", header, 179, max(xs), min(xs), max(ys), min(ys), max(zs), min(zs))
    with open(path, "wb") as f:
        f.write(header)
        for x, y, z, c in points:
            f.write(struct.pack("<3iHBBbBH", round((x - offset[0]) / scale),
                                round((y - offset[1]) / scale), round((z - offset[2]) / scale),
                                0, 0x09, c, 0, 0, 0))


def val3dity_valid(val3dity, seqs, name):
    """The features val3dity finds valid in the CityJSONSeq files `seqs` (asserting every one
    is); None when the validator is absent."""
    if not os.path.exists(val3dity):
        return None
    valid = 0
    for seq in seqs:
        report = seq + ".val3dity.json"
        v = subprocess.run([val3dity, seq, "--report", report], capture_output=True, text=True)
        assert os.path.exists(report), (v.stdout, v.stderr)
        for feature in json.load(open(report))["features"]:
            assert feature["validity"], (name, feature)
            valid += 1
    return valid


def run_city(binary, work, name, tile, extra):
    """`csgtile run` of `tile` (RD New + NAP) with `extra` YAML appended to its config, into
    WORK/NAME; asserts it succeeds and that no cell names a problem. Returns the run's
    directory and the objects of its cells' manifests."""
    config = os.path.join(work, f"{name}.yaml")
    with open(config, "w") as f:
        f.write(f"run:\n  name: {name}\n  inputs:\n    - {tile}\n  output: {work}/{name}\n"
                f"  crs: EPSG:28992+5709\n{extra}log:\n  level: warn\n")
    p = subprocess.run([binary, "run", config, "--json"], capture_output=True, text=True)
    assert p.returncode == 0, (name, p.returncode, p.stdout, p.stderr)
    rundir = f"{work}/{name}/runs/{name}"
    objects = []
    for m in glob.glob(f"{rundir}/cells/*/manifest.json"):
        cell = json.load(open(m))
        assert not cell["problems"], (name, cell["problems"])
        objects += cell["objects"]
    return rundir, objects


def city_objects(rundir):
    """The run's CityJSONSeq files and every (id, CityObject) in their features."""
    seqs = glob.glob(f"{rundir}/cells/*/model.city.jsonl")
    objects = []
    for seq in seqs:
        with open(seq) as f:
            for line in f.readlines()[1:]:
                objects += json.loads(line)["CityObjects"].items()
    return seqs, objects
