#!/usr/bin/python3
"""scripts/run builds what it runs, not the whole tree: on a fresh machine its first run serves
once the server has compiled, not after the test suite has (22 of 28 minutes went to the suite
when it built everything).

Checks that scripts/run hands scripts/setup the targets it runs and that each is a target of this
build, and counts the compilations each needs: the run's targets must need fewer than half of
what `all` needs. Usage: run_builds_what_it_runs.py SOURCE_DIR BUILD_DIR (a Ninja build).
"""
import re
import shlex
import subprocess
import sys

source_dir, build_dir = sys.argv[1:3]
script = open(f"{source_dir}/scripts/run", encoding="utf-8").read()
calls = [line for line in script.splitlines() if re.match(r"\s*\./scripts/setup\b", line)]
if len(calls) != 1:
    sys.exit(f"FAIL: scripts/run calls scripts/setup {len(calls)} times, not once")
words = shlex.split(calls[0])
targets = words[2:]
if len(words) < 3 or not targets:
    sys.exit(f"FAIL: scripts/run builds everything ({calls[0].strip()!r}): name the targets it runs")
if "hapticd" not in targets:
    sys.exit(f"FAIL: scripts/run does not build hapticd: {targets}")
known = subprocess.run(["ninja", "-C", build_dir, "-t", "targets", "all"], capture_output=True, text=True,
                       check=True).stdout
known = {line.split(":")[0] for line in known.splitlines()}
missing = [t for t in targets if t not in known]
if missing:
    sys.exit(f"FAIL: scripts/run names targets this build does not have: {missing}")


def compilations(*names):
    commands = subprocess.run(["ninja", "-C", build_dir, "-t", "commands", *names], capture_output=True,
                              text=True, check=True).stdout
    return sum(1 for line in commands.splitlines() if " -c " in line)


run, everything = compilations(*targets), compilations("all")
print(f"scripts/run builds {', '.join(targets)}: {run} of the {everything} compilations of a full build")
if run * 2 >= everything:
    sys.exit("FAIL: scripts/run's targets need half the build or more")
