#!/usr/bin/env python3
"""clang-tidy over the project's translation units, skipping those already found clean.

Usage: tidy_cached.py BUILD_DIR REGEX [JOBS] [--baseline FILE]

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

With --baseline FILE (.ci/tidy-baseline: a commit at which every unit was found clean, and the
clang-tidy that found it), only the units that changed since that commit are checked: those whose
source, or any file the build's compiler read for them (Ninja's dependency log), differs between
the commit and the working tree. Every unit is checked instead when the commit is not in the
history, the clang-tidy differs, or a file that changes every unit's check changed since (a
.clang-tidy, the shared flags, this script: EVERY_UNIT). On a machine without the cache (a fresh CI
machine) a full check costs about 27 minutes on 2 cores (2026-12-07); this is the lint a pull
request's CI runs on what it changes.
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


# A change to one of these can change the check of every unit: the checks, the flags every
# target shares (cmake/SelfsenseBuild.cmake, the top CMakeLists.txt) and this script. A folder's
# CMakeLists.txt that adds a target or a file changes no other unit's command.
EVERY_UNIT = re.compile(r"(^|/)\.clang-tidy$|^CMakeLists\.txt$|^cmake/SelfsenseBuild\.cmake$|"
                        r"^scripts/tidy_cached\.py$")


def read_baseline(path):
    """(commit, clang-tidy's first version line) from a baseline file; '#' lines are comments."""
    with open(path, encoding="utf-8") as f:
        lines = [l.strip() for l in f if l.strip() and not l.startswith("#")]
    if len(lines) != 2:
        sys.exit(f"tidy_cached: {path}: expected a commit and a clang-tidy version line")
    return lines[0], lines[1]


def changed_since(root, commit):
    """Absolute paths that differ between COMMIT and the working tree (untracked files too), or
    None when COMMIT is not in the history."""
    diff = subprocess.run(["git", "-C", root, "diff", "--name-only", commit, "--"],
                          capture_output=True, text=True)
    if diff.returncode != 0:
        return None
    untracked = subprocess.run(["git", "-C", root, "ls-files", "--others", "--exclude-standard"],
                               capture_output=True, text=True, check=True)
    return set((diff.stdout + untracked.stdout).split())


def object_of(entry):
    args = entry["arguments"] if "arguments" in entry else shlex.split(entry["command"])
    for i, a in enumerate(args[:-1]):
        if a == "-o":
            return args[i + 1]
    return None


def changed_units(build, root, entries, baseline, version):
    """(the entries to check, how many were left as clean at the baseline, a line saying why)."""
    commit, wanted = read_baseline(baseline)
    have = version.decode().strip().splitlines()[0].strip()
    if have != wanted:
        return entries, 0, f"tidy_cached: every unit ({have}; the baseline's is {wanted})"
    changed = changed_since(root, commit)
    if changed is None:
        return entries, 0, f"tidy_cached: every unit (the baseline {commit} is not in the history)"
    every = sorted(p for p in changed if EVERY_UNIT.search(p))
    if every:
        return entries, 0, (f"tidy_cached: every unit ({', '.join(every[:3])} changed since the "
                            f"baseline {commit[:12]})")
    changed = {os.path.join(root, p) for p in changed}
    deps = ninja_deps(build)
    kept = []
    for entry in entries:
        source = os.path.normpath(os.path.join(entry["directory"], entry["file"]))
        obj = object_of(entry)
        listed = None
        if obj is not None:
            obj_path = os.path.normpath(os.path.join(entry["directory"], obj))
            listed = deps.get(os.path.relpath(obj_path, os.path.abspath(build)))
        if listed is None:
            kept.append(entry)  # what it reads is unknown: checked
            continue
        read = {os.path.normpath(os.path.join(os.path.abspath(build), d)) for d in listed}
        if source in changed or read & changed:
            kept.append(entry)
    return kept, len(entries) - len(kept), (
        f"tidy_cached: the {len(kept)} of {len(entries)} units that changed since the baseline "
        f"{commit[:12]} ({len(changed)} files changed)")


def main():
    args = sys.argv[1:]
    baseline = None
    if "--baseline" in args:
        i = args.index("--baseline")
        baseline = args[i + 1]
        del args[i:i + 2]
    build, pattern = args[0], re.compile(args[1])
    jobs = int(args[2]) if len(args) > 2 else os.cpu_count() or 1
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # scripts/..
    with open(os.path.join(build, "compile_commands.json"), encoding="utf-8") as f:
        entries = [e for e in json.load(f) if pattern.search(e["file"])]
    cache = cache_dir(build)
    version = subprocess.run(["clang-tidy", "--version"], capture_output=True, check=True).stdout
    skipped, since = 0, ""
    if baseline:
        entries, skipped, since = changed_units(build, root, entries, baseline, version)
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
    if since:
        print(since)
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        for outcome, output in pool.map(check, entries):
            counts[outcome] += 1
            if output:
                print(output)
    print(f"clang-tidy: {len(entries)} units, {counts['checked']} checked, "
          f"{counts['cached']} clean before (cache {cache}), {counts['finding']} with findings"
          + (f"; {skipped} unchanged since the baseline" if skipped else ""))
    return 1 if counts["finding"] else 0


if __name__ == "__main__":
    sys.exit(main())
