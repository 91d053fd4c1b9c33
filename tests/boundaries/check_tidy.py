#!/usr/bin/env python3
"""clang-tidy (the repository's .clang-tidy, warnings as errors) on every translation unit of
kernel/, geo/, config/ and worker/ that BUILD_DIR's compile_commands.json lists, or on the FILES
given. Usage: check_tidy.py BUILD_DIR [FILES...]. Exit 1 with every diagnostic printed.

Jobs: CSGTILE_TIDY_JOBS (default: the cores). The headers of those directories are checked
through the units that include them (HeaderFilterRegex).

A unit found clean is remembered under a key: the hash of clang-tidy's version, .clang-tidy, the
unit's path and its preprocessed text with comments (clang++ -E -C, so every header it includes
and every NOLINT is part of it; the checkout's and the build's paths replaced by placeholders, so
a clone elsewhere finds the same keys). A unit whose key is remembered is not analysed again: its
text is the same text that was found clean, by the same tool with the same checks. Only clean
results are remembered; a unit with diagnostics is analysed every time. The cache lives in
CSGTILE_TIDY_CACHE (default ~/.cache/csgtile-tidy); CSGTILE_TIDY_CACHE=off analyses every unit.
"""
import concurrent.futures
import hashlib
import json
import os
import re
import shlex
import shutil
import subprocess
import sys

DIRS = ("kernel", "geo", "config", "worker")
DIAGNOSTIC = re.compile(r"(warning|error):")


def units_of(build, root):
    entries = {}
    for entry in json.load(open(os.path.join(build, "compile_commands.json"))):
        path = os.path.realpath(os.path.join(entry["directory"], entry["file"]))
        rel = os.path.relpath(path, root)
        if rel.split(os.sep)[0] in DIRS:
            entries[rel] = entry
    return entries


def preprocess_command(entry, path):
    args = entry["arguments"] if "arguments" in entry else shlex.split(entry["command"])
    out = ["clang++"]
    skip = False
    for arg in args[1:]:
        if skip:
            skip = False
            continue
        if arg in ("-o", "-c"):
            skip = arg == "-o"
            continue
        if os.path.realpath(os.path.join(entry["directory"], arg)) == path:
            continue
        out.append(arg)
    return out + ["-Wno-unknown-warning-option", "-E", "-C", path]


def main():
    if len(sys.argv) < 2:
        sys.exit("usage: check_tidy.py BUILD_DIR [FILES...]")
    build = os.path.realpath(sys.argv[1])
    root = os.path.realpath(os.path.join(os.path.dirname(__file__), "..", ".."))
    tool = os.environ.get("CLANG_TIDY", "clang-tidy")
    if shutil.which(tool) is None:
        sys.exit(f"clang-tidy not found ('{tool}'): apt-get install clang-tidy "
                 "(deploy/setup.sh installs it)")
    if not os.path.isfile(os.path.join(build, "compile_commands.json")):
        sys.exit(f"{build}/compile_commands.json missing: configure with CMake first")
    entries = units_of(build, root)
    if len(sys.argv) > 2:
        wanted = [os.path.relpath(os.path.realpath(f), root) for f in sys.argv[2:]]
    else:
        wanted = sorted(entries)
    jobs = int(os.environ.get("CSGTILE_TIDY_JOBS", os.cpu_count() or 1))
    cache = os.environ.get("CSGTILE_TIDY_CACHE",
                           os.path.join(os.path.expanduser("~"), ".cache", "csgtile-tidy"))
    if cache == "off":
        cache = None
    else:
        os.makedirs(cache, exist_ok=True)
    version = subprocess.run([tool, "--version"], capture_output=True, text=True).stdout
    config = open(os.path.join(root, ".clang-tidy"), "rb").read()
    extra = "--extra-arg=-Wno-unknown-warning-option"

    def key_of(rel):
        entry = entries.get(rel)
        if entry is None:
            return None
        path = os.path.join(root, rel)
        pre = subprocess.run(preprocess_command(entry, path), cwd=entry["directory"],
                             capture_output=True)
        if pre.returncode != 0:
            return None
        text = pre.stdout.replace(build.encode(), b"@BUILD@").replace(root.encode(), b"@ROOT@")
        h = hashlib.sha256()
        for part in (version.encode(), config, extra.encode(), rel.encode(), text):
            h.update(len(part).to_bytes(8, "little"))
            h.update(part)
        return h.hexdigest()

    def check(rel):
        key = key_of(rel) if cache else None
        if key and os.path.exists(os.path.join(cache, key)):
            return rel, [], True
        run = subprocess.run([tool, "-p", build, "--quiet", extra, rel], cwd=root,
                             capture_output=True, text=True)
        lines = [ln for ln in (run.stdout + run.stderr).splitlines() if DIAGNOSTIC.search(ln)]
        if run.returncode != 0 and not lines:
            lines = [f"{rel}: error: clang-tidy exited with {run.returncode}"]
        if key and not lines:
            open(os.path.join(cache, key), "w").close()
        return rel, lines, False

    diagnostics = set()
    cached = 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        for _, lines, hit in pool.map(check, wanted):
            diagnostics.update(lines)
            cached += hit
    if diagnostics:
        print("\n".join(sorted(diagnostics)))
        print(f"clang-tidy: {len(diagnostics)} diagnostics in {len(wanted)} units",
              file=sys.stderr)
        return 1
    print(f"clang-tidy: {len(wanted)} units clean ({cached} unchanged since found clean)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
