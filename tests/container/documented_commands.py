#!/usr/bin/python3
"""Runs every container `run` command the documentation gives, as typed, and checks what listens.

The image's own configuration binds 0.0.0.0 without TLS or tokens, so a documented command is safe
only if it publishes the ports on the host's loopback address (or mounts a configuration of the
host's own, with `security`, and publishes on one named address). Each `docker run` / `podman run`
in a fenced shell block of README.md, docker/README.md and docs/*.md is:

  * run, when it uses the image's configuration: `docker` becomes `podman --runtime runc` (no
    Docker daemon here; podman takes the same arguments), the image name becomes the image under
    test and the container's name a unique one. Once it serves (or after 20 s), every listener on
    the host's ports 50051/tcp and 50052/udp must be on 127.0.0.1 or ::1, and one must exist;
  * checked as written, when it mounts /etc/hapticd (a host configuration that cannot exist here):
    each `-p` must name an address, and not 0.0.0.0, and `--network host` must be absent.

Usage: documented_commands.py <source-dir> <image> <hapticd binary> [podman run option ...]
Exit 0 when every command is safe, 1 naming the command and the listener otherwise.
"""
import glob
import os
import re
import shlex
import subprocess
import sys
import time

CONTROL_PORT = 50051
DATA_PORT = 50052
LOOPBACK = {"127.0.0.1", "::1", "[::1]"}
# Options of `run` that take a value: the image is the first word that is neither one of these nor
# an option.
VALUE_OPTIONS = {"--name", "-p", "--publish", "-v", "--volume", "--ulimit", "--network", "--net",
                 "--runtime", "-e", "--env", "--entrypoint", "--health-cmd", "--cap-add", "-u",
                 "--user", "--mount"}


def documented_run_commands(source_dir):
    """(file, line, argv) for each container run command in a fenced sh block."""
    files = [os.path.join(source_dir, "README.md"), os.path.join(source_dir, "docker/README.md")]
    files += sorted(glob.glob(os.path.join(source_dir, "docs/*.md")))
    found = []
    for path in files:
        if not os.path.exists(path):
            continue
        in_block = False
        pending, pending_line = "", 0
        for number, line in enumerate(open(path, encoding="utf-8"), start=1):
            if line.startswith("```"):
                in_block = not in_block and line.strip() in ("```sh", "```bash", "```console")
                pending = ""
                continue
            if not in_block:
                continue
            if not pending:
                pending_line = number
            pending += line.rstrip("\n")
            if pending.endswith("\\"):
                pending = pending[:-1] + " "
                continue
            command = pending.split(" #")[0].strip()
            pending = ""
            try:
                argv = shlex.split(command)
            except ValueError:
                continue
            if not argv:
                continue
            if argv[0] == "docker" and argv[1:2] == ["run"]:
                found.append((os.path.relpath(path, source_dir), pending_line, argv))
            elif argv[0] == "podman" and "run" in argv[1:4] and "healthcheck" not in argv:
                found.append((os.path.relpath(path, source_dir), pending_line, argv))
    return found


def option_values(argv, names):
    values = []
    for index, word in enumerate(argv):
        if word in names and index + 1 < len(argv):
            values.append(argv[index + 1])
        for name in names:
            if word.startswith(name + "="):
                values.append(word.split("=", 1)[1])
    return values


def check_as_written(argv):
    """Problems with a command that mounts the host's own configuration (not run here)."""
    problems = []
    if "host" in option_values(argv, {"--network", "--net"}):
        problems.append("--network host puts the listener on every host interface")
    for published in option_values(argv, {"-p", "--publish"}):
        parts = published.split(":")
        if len(parts) < 3 or parts[0] in ("", "0.0.0.0", "[::]"):
            problems.append(f"-p {published} publishes on every host interface")
    return problems


def as_runnable(argv, image, run_options, index):
    """The documented command with podman for docker, the image under test and a unique name."""
    if argv[0] == "docker":
        argv = ["podman", "--runtime", "runc"] + argv[1:]
    run_at = argv.index("run")
    words = argv[run_at + 1:]
    result = argv[:run_at + 1]
    if "--ulimit" not in words:
        result += run_options
    image_seen = False
    skip_value = False
    for position, word in enumerate(words):
        if skip_value:
            skip_value = False
            previous = words[position - 1]
            result.append(f"hapticd-documented-{index}" if previous == "--name" else word)
            continue
        if not image_seen and word in VALUE_OPTIONS:
            skip_value = True
            result.append(word)
            continue
        if not image_seen and not word.startswith("-"):
            image_seen = True
            result.append(image)
            continue
        result.append(word)
    return result


def listeners(ports):
    """(protocol, local address, port) of every TCP listener and UDP socket on the given ports."""
    output = subprocess.run(["ss", "-H", "-l", "-n", "-t", "-u"], capture_output=True, text=True,
                            check=True).stdout
    found = []
    for line in output.splitlines():
        fields = line.split()
        if len(fields) < 5:
            continue
        address, _, port = fields[4].rpartition(":")
        if port.isdigit() and int(port) in ports:
            found.append((fields[0], address.split("%")[0], int(port)))
    return found


def main():
    source_dir, image, hapticd = sys.argv[1:4]
    run_options = sys.argv[4:]
    commands = documented_run_commands(source_dir)
    if not commands:
        print("FAIL: no documented container run command found")
        return 1
    occupied = listeners({CONTROL_PORT, DATA_PORT})
    if occupied:
        print(f"FAIL: something already listens on {CONTROL_PORT}/{DATA_PORT} ({occupied}); the "
              "documented commands publish those ports, so stop it first")
        return 1
    failures = 0
    for index, (path, line, argv) in enumerate(commands):
        where = f"{path}:{line}"
        if "/etc/hapticd" in " ".join(option_values(argv, {"-v", "--volume", "--mount"})):
            problems = check_as_written(argv)
            verdict = "; ".join(problems) if problems else "publishes on a named address"
            print(f"{where}: mounts the host's configuration, checked as written: {verdict}")
            failures += bool(problems)
            continue
        runnable = as_runnable(argv, image, run_options, index)
        print(f"{where}: running {shlex.join(runnable)}")
        started = subprocess.run(runnable, capture_output=True, text=True)
        if started.returncode != 0:
            print(f"FAIL {where}: the command failed: {started.stderr.strip()[-400:]}")
            failures += 1
            continue
        container = f"hapticd-documented-{index}"
        try:
            deadline = time.monotonic() + 20
            while time.monotonic() < deadline:
                check = subprocess.run([hapticd, "--health-check", f"127.0.0.1:{CONTROL_PORT}"],
                                       capture_output=True, text=True, timeout=10)
                if check.returncode == 0:
                    break
                time.sleep(0.25)
            found = listeners({CONTROL_PORT, DATA_PORT})
            print(f"{where}: listening: {', '.join(f'{p} {a}:{n}' for p, a, n in found) or 'nothing'}")
            exposed = [f"{p} {a}:{n}" for p, a, n in found if a not in LOOPBACK]
            if exposed:
                print(f"FAIL {where}: the image's unauthenticated ports listen beyond loopback: "
                      f"{', '.join(exposed)}")
                failures += 1
            elif not any(n == CONTROL_PORT for _, _, n in found):
                print(f"FAIL {where}: nothing listens on {CONTROL_PORT} on this host")
                failures += 1
        finally:
            subprocess.run(["podman", "--runtime", "runc", "rm", "-f", "-t", "2", container],
                           capture_output=True)
            for _ in range(50):
                if not listeners({CONTROL_PORT, DATA_PORT}):
                    break
                time.sleep(0.1)
    if failures:
        print(f"FAIL: {failures} of {len(commands)} documented container commands are unsafe as typed")
        return 1
    print(f"PASS: all {len(commands)} documented container run commands publish only on loopback "
          "or on a named address with the host's configuration")
    return 0


if __name__ == "__main__":
    sys.exit(main())
