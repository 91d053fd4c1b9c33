"""Scene inputs for the worker fault tests (chaos_workers.py, sigterm_storm.py): healthy jobs
of a fraction of a second each — a row of boxes and posts fused — placed tens of metres apart, so that
jobs have no relations between them and publishing stays linear in the job count."""
import json
import os


def write_jobs(directory, count, posts=4):
    """Writes `count` scene files into `directory`, each a row of `posts` boxes and posts
    (about 0.1 s of work per 4); returns their paths in job order."""
    os.makedirs(directory, exist_ok=True)
    inputs = []
    for k in range(count):
        x0 = (10.0 + posts) * 4.0 * (k % 25)
        y0 = 40.0 * (k // 25)
        prims = []
        for i in range(posts):
            s = 1.0 + ((k + i) % 7) * 0.1
            prims.append({"type": "box", "size": [s, s, 2.0],
                          "placement": [[1, 0, 0, x0 + 0.8 * i], [0, 1, 0, y0], [0, 0, 1, 0]]})
            prims.append({"type": "cylinder", "r": 0.3, "h": 3.0,
                          "placement": [[1, 0, 0, x0 + 0.8 * i + s / 2], [0, 1, 0, y0 + s / 2],
                                        [0, 0, 1, 0]]})
        path = f"{directory}/job-{k:04d}.json"
        with open(path, "w") as f:
            json.dump({"name": f"job-{k}", "op": "fuse", "primitives": prims}, f)
        inputs.append(path)
    return inputs
