#!/usr/bin/env python3
"""clang-tidy over the project's translation units, skipping those already found clean.

Usage: tidy_cached.py BUILD_DIR REGEX [JOBS]

A unit is skipped when the same clang-tidy, the same .clang-tidy files, the same compile command
and the same preprocessed source (every header it includes, the source root written as @ROOT@ so
a clone elsewhere hits too) were found clean before. Only clean results are cached: a unit with a
finding runs again next time.

Two keys name the same unit: the preprocessed source's, and (as ccache's direct mode) the
contents of the files the build's compiler read for it (Ninja's dependency log, `ninja -t deps`),
used only when the unit's object is newer than every one of them (the build is up to date for
it). The second needs no preprocessor: a run in which nothing changed reads files instead of
preprocessing every unit. A unit found clean under either key gets both stamps. Cache: $SELFSENSE_TIDY_CACHE, else /var/cache/selfsense-tidy when
writable, else BUILD_DIR/tidy-cache. Exit 1 when any unit has a finding (its output is printed).
"""
import concurrent.futures
import hashlib
import json
import os
import re
import shlex
import subprocess
import sys


def cache_dir(build):
    wanted = os.environ.get("SELFSENSE_TIDY_CACHE")
    candidates = [wanted] if wanted else ["/var/cache/selfsense-tidy"]
    candidates.append(os.path.join(build, "tidy-cache"))
    for path in candidates:
        try:
            os.makedirs(path, exist_ok=True)
            if os.access(path, os.W_OK):
                return path
        except OSError:
            continue
    sys.exit("tidy_cached: no writable cache directory")


def preprocess_command(entry):
    args = entry["arguments"] if "arguments" in entry else shlex.split(entry["command"])
    out = []
    skip = False
    for a in args:
        if skip:
            skip = False
            continue
        if a == "-o":
            skip = True
            continue
        if a == "-c":
            continue
        out.append(a)
    return out + ["-E", "-P", "-o", "-"]


def ninja_deps(build):
    """{object path relative to BUILD: [dependency paths as Ninja wrote them]} from Ninja's log."""
    run = subprocess.run(["ninja", "-C", build, "-t", "deps"], capture_output=True, text=True)
    deps, current = {}, None
    if run.returncode != 0:
        return deps
    for line in run.stdout.splitlines():
        if not line.startswith(" ") and "#deps" in line:
            target, rest = line.split(": #deps", 1)
            current = [] if rest.rstrip().endswith("(VALID)") else None
            if current is not None:
                deps[target] = current
        elif line.strip() and current is not None:
            current.append(line.strip())
    return deps


def object_of(entry):
    args = entry["arguments"] if "arguments" in entry else shlex.split(entry["command"])
    for i, a in enumerate(args[:-1]):
        if a == "-o":
            return args[i + 1]
    return None


def main():
    build, pattern = sys.argv[1], re.compile(sys.argv[2])
    jobs = int(sys.argv[3]) if len(sys.argv) > 3 else os.cpu_count() or 1
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # scripts/..
    with open(os.path.join(build, "compile_commands.json"), encoding="utf-8") as f:
        entries = [e for e in json.load(f) if pattern.search(e["file"])]
    cache = cache_dir(build)
    version = subprocess.run(["clang-tidy", "--version"], capture_output=True, check=True).stdout
    config = b""  # every .clang-tidy of the sources (a unit's own and its parents')
    found = []
    for base, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if d in ("src", "tests", "drivers", "include")
                   or os.path.relpath(base, root) != "."]
        if ".clang-tidy" in files:
            found.append(os.path.join(base, ".clang-tidy"))
    for path in sorted(found):
        with open(path, "rb") as f:
            config += os.path.relpath(path, root).encode() + b"\0" + f.read()
    root_bytes = root.encode()
    deps = ninja_deps(build)
    digests = {}  # path -> (mtime_ns, sha256 of its content); threads may fill it twice, harmlessly

    def digest(path):
        st = os.stat(path)
        known = digests.get(path)
        if known and known[0] == st.st_mtime_ns:
            return known
        with open(path, "rb") as f:
            known = (st.st_mtime_ns, hashlib.sha256(f.read()).digest())
        digests[path] = known
        return known

    def direct_stamp(entry, command):
        """The unit's stamp from the files its compiler read, or None when unknown or stale."""
        obj = object_of(entry)
        if obj is None:
            return None
        obj_path = os.path.normpath(os.path.join(entry["directory"], obj))
        listed = deps.get(os.path.relpath(obj_path, os.path.abspath(build)))
        if not listed:
            return None
        try:
            built = os.stat(obj_path).st_mtime_ns
            key = hashlib.sha256(b"direct\0" + version + config + command)
            for dep in listed:
                path = os.path.normpath(os.path.join(os.path.abspath(build), dep))
                mtime, content = digest(path)
                if mtime > built:
                    return None  # changed since the build: its includes may have too
                key.update(path.encode().replace(root_bytes, b"@ROOT@") + b"\0" + content)
        except OSError:
            return None
        return os.path.join(cache, key.hexdigest())

    def check(entry):
        command = " ".join(preprocess_command(entry)).encode().replace(root_bytes, b"@ROOT@")
        direct = direct_stamp(entry, command)
        if direct and os.path.exists(direct):
            return "cached", ""
        pre = subprocess.run(preprocess_command(entry), cwd=entry["directory"],
                             capture_output=True)
        key = hashlib.sha256(version + config)
        if pre.returncode == 0:
            key.update(command)
            key.update(pre.stdout.replace(root_bytes, b"@ROOT@"))
            stamp = os.path.join(cache, key.hexdigest())
            if os.path.exists(stamp):
                if direct:
                    with open(direct, "w", encoding="utf-8"):
                        pass
                return "cached", ""
        else:
            stamp = None  # not preprocessable here: always checked
        run = subprocess.run(["clang-tidy", "-p", build, "--quiet", entry["file"]],
                             capture_output=True, text=True)
        output = run.stdout + run.stderr
        clean = run.returncode == 0 and not re.search(r"(warning|error):", output)
        if not clean:
            return "finding", output or f"clang-tidy exited {run.returncode}"
        for path in (stamp, direct):
            if path:
                with open(path, "w", encoding="utf-8"):
                    pass
        return "checked", ""

    counts = {"cached": 0, "checked": 0, "finding": 0}
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        for outcome, output in pool.map(check, entries):
            counts[outcome] += 1
            if output:
                print(output)
    print(f"clang-tidy: {len(entries)} units, {counts['checked']} checked, "
          f"{counts['cached']} clean before (cache {cache}), {counts['finding']} with findings")
    return 1 if counts["finding"] else 0


if __name__ == "__main__":
    sys.exit(main())
