#!/usr/bin/env python3
"""Runs the code snippets of README.md and docs/*.md as they are written.

Every fenced block in those files carries a one-line HTML comment right above it that says what it
is, so a new block cannot go untested by accident (`doc.annotations` fails on one without):

    <!-- snippet: NAME run=sh server="./build/server/app/hapticd --lockstep" expect=OUT -->
    <!-- snippet: OUT output -->
    <!-- snippet: NAME skip="why it cannot run in a test" -->
    <!-- snippet: NAME shows="what it is: a diagram, a log line, a layout" -->

The snippets of one `group` (default: the snippet alone) run in document order in one sandbox,
as one ctest entry `doc.<file>.<group>`. The sandbox is a mount and network namespace of its own
(root only; elsewhere the test is skipped): /etc, /usr, /opt and /var are copy-on-write overlays,
/root (HOME) and /home fresh, loopback up with the docs' example addresses on it and
their names in /etc/hosts, so a snippet runs as written (`useradd`, `/etc/hapticd`, port 50051,
`haptics-server.lab`) and leaves nothing behind. The working directory holds the source tree's
entries and `build` (the build directory under test).

Attributes:
  run=sh|python|cpp   sh: one bash script (`set -eo pipefail`); the working directory, exported
                      variables and umask carry on to the group's next sh snippet. python: the
                      group's python snippets run one after another in one interpreter, as in a
                      notebook. cpp: the program CMake built from the snippet (wrap=main puts
                      statements into main(), wrap=fields designated initializers into a
                      haptic::ClientConfig; helpers=NAME lends them what precedes main() in NAME).
  server=CMD          start CMD in the background before this snippet (after its file=), kept
                      until the group ends; waits until `server-ready` (default 127.0.0.1:50051)
                      accepts. Python snippets see the build's package (PYTHONPATH=build/python).
  server-user=USER    run the server as USER.
  before=CMD          a shell step the prose describes but shows no block for (copying a file
                      to the client, say); runs before the snippet.
  stream=SECONDS      sh only: run line by line (each line's exports carry on); a line still
                      running SECONDS after its first output is sent SIGINT and must then exit 0
                      (`--watch`, `events`). One that prints nothing in 60 s fails.
  expect=OUT          the snippet's output must match the `output` block OUT: each run of lines
                      between `...` lines appears in order, the first at the start and the last at
                      the end unless a `...` stands there. expect-lines=A-B compares the block's
                      lines A to B only (1-based; the rows without another program's header and
                      footer, say), anchored at neither end.
  expect=comments     python: the trailing comment of each print() line is the line it prints.
                      sh: each comment line after the first command is a line of the output.
                      In sh, a trailing `# expect: TEXT` requires TEXT in the output in any case.
  output from=CMD     an output block of its own: CMD runs in the sandbox where the block stands
                      in the group (a failing start, say), and what it prints must show the block's
                      lines, anchored at neither end; status=N also requires its exit status.
  file=PATH           write the block to PATH (a configuration file, say); check=config then
                      has the group's hapticd read it (`--print-config`).
  in-tree             sh: start in the source tree's top (where the prose says so), whatever
                      directory the group's earlier snippets left.
  after=NAME          run it right after the group's snippet NAME rather than where it stands
                      (an example that needs what a later section sets up).
  timeout=SECONDS     for the snippet (default 120).

Log lines are compared without the time stamp and level in front (`[2026-…] [info] `).

Usage:
  doc_snippets.py check SOURCE               every block annotated, every reference resolved
  doc_snippets.py list SOURCE                the groups (for CMake; ":install" marks one that installs)
  doc_snippets.py cpp-list SOURCE            the C++ programs (for CMake)
  doc_snippets.py extract SOURCE ID OUT.cpp  write one C++ program
  doc_snippets.py run SOURCE GROUP --build DIR --programs DIR [--python-preload LIBS]
"""

from __future__ import annotations

import os
import re
import select
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

SKIP = 77
ANNOTATION = re.compile(r"^\s*<!--\s*snippet:\s*(.*?)\s*-->\s*$")
FENCE = re.compile(r"^(\s*)(```+)\s*([^\s`]*)")
KINDS_RUN = {"sh", "python", "cpp"}
KNOWN = {"run", "skip", "shows", "output", "group", "server", "server-user", "server-ready", "helpers", "after", "in-tree",
         "before", "stream", "expect", "expect-lines", "file", "check", "wrap", "timeout", "from", "status"}
# The docs' example hosts: names and addresses that must reach the sandbox's own server.
EXAMPLE_HOSTS = {"192.168.10.20": ["haptics-server.lab"], "127.0.0.1": ["hapticd-host", "lab-server"]}


LOG_STAMP = re.compile(r"^\[\d{4}-\d\d-\d\d [\d:.]+\] \[\w+\] ")


class SnippetError(Exception):
    pass


@dataclass
class Snippet:
    doc: str              # path relative to the source root, e.g. docs/deployment.md
    line: int             # line of the opening fence, 1-based
    name: str
    attrs: dict[str, str]
    code: str
    lang: str

    @property
    def where(self) -> str:
        return f"{self.doc}:{self.line} ({self.name})"

    @property
    def run(self) -> str | None:
        return self.attrs.get("run")

    @property
    def group(self) -> str:
        return self.attrs.get("group", self.name)

    @property
    def program_id(self) -> str:
        return re.sub(r"[^A-Za-z0-9_]", "_", f"{doc_stem(self.doc)}_{self.name}")


def doc_stem(doc: str) -> str:
    return Path(doc).stem.lower()


def documents(source: Path) -> list[str]:
    docs = ["README.md"] + sorted(str(p.relative_to(source)) for p in (source / "docs").glob("*.md"))
    return [d for d in docs if (source / d).is_file()]


def parse(source: Path, doc: str) -> tuple[list[Snippet], list[str]]:
    """The annotated blocks of one document, and the problems found (unannotated blocks...)."""
    lines = (source / doc).read_text(encoding="utf-8").split("\n")
    snippets, problems = [], []
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, ticks, lang = m.group(1), m.group(2), m.group(3)
        end = i + 1
        while end < len(lines) and not lines[end].strip().startswith(ticks):
            end += 1
        if end == len(lines):
            problems.append(f"{doc}:{i + 1}: a fence that is never closed")
            break
        body = [ln[len(indent):] if ln.startswith(indent) else ln.lstrip() for ln in lines[i + 1:end]]
        previous = i - 1
        while previous >= 0 and not lines[previous].strip():
            previous -= 1
        a = ANNOTATION.match(lines[previous]) if previous >= 0 else None
        if not a:
            problems.append(f"{doc}:{i + 1}: a ```{lang} block without a <!-- snippet: NAME ... --> "
                            "line above it (run=, skip=, shows= or output: tests/docs/doc_snippets.py)")
        else:
            try:
                words = shlex.split(a.group(1))
            except ValueError as error:
                problems.append(f"{doc}:{previous + 1}: snippet annotation: {error}")
                words = []
            if words:
                attrs = {}
                for word in words[1:]:
                    key, _, value = word.partition("=")
                    if key not in KNOWN:
                        problems.append(f"{doc}:{previous + 1}: snippet {words[0]}: unknown attribute "
                                        f"'{key}' (known: {', '.join(sorted(KNOWN))})")
                    attrs[key] = value if _ else "yes"
                snippets.append(Snippet(doc, i + 1, words[0], attrs, "\n".join(body) + "\n", lang))
        i = end + 1
    return snippets, problems


def load(source: Path) -> tuple[list[Snippet], list[str]]:
    every, problems = [], []
    for doc in documents(source):
        snippets, found = parse(source, doc)
        every += snippets
        problems += found
    seen: dict[tuple[str, str], Snippet] = {}
    for s in every:
        key = (s.doc, s.name)
        if key in seen:
            problems.append(f"{s.where}: the name is taken by {seen[key].where}")
        seen[key] = s
        kinds = [k for k in ("run", "skip", "shows", "output") if k in s.attrs]
        if len(kinds) != 1 and not (not kinds and "file" in s.attrs):
            problems.append(f"{s.where}: give exactly one of run=, skip=, shows=, output, or file= "
                            f"(got {kinds or 'none'})")
        if s.run and s.run not in KINDS_RUN:
            problems.append(f"{s.where}: run={s.run}: one of {', '.join(sorted(KINDS_RUN))}")
        for reason in ("skip", "shows"):
            if s.attrs.get(reason) == "yes":
                problems.append(f"{s.where}: {reason}= needs a reason in quotes")
        expect = s.attrs.get("expect")
        if expect and expect != "comments":
            target = seen.get((s.doc, expect))
            target = target or next((t for t in every if t.doc == s.doc and t.name == expect), None)
            if target is None or "output" not in target.attrs:
                problems.append(f"{s.where}: expect={expect}: no `output` block of that name in {s.doc}")
        if s.attrs.get("check") == "config" and "file" not in s.attrs:
            problems.append(f"{s.where}: check=config needs file=PATH")
        if s.run == "cpp" and s.attrs.get("wrap", "none") not in ("none", "main", "fields"):
            problems.append(f"{s.where}: wrap={s.attrs['wrap']}: main, fields or none")
        helpers = s.attrs.get("helpers")
        if helpers and not any(t.doc == s.doc and t.name == helpers and t.run == "cpp" for t in every):
            problems.append(f"{s.where}: helpers={helpers}: no C++ snippet of that name in {s.doc}")
    for s in every:
        if "status" in s.attrs and "from" not in s.attrs:
            problems.append(f"{s.where}: status= goes with from=")
        if "from" in s.attrs and "output" not in s.attrs:
            problems.append(f"{s.where}: from= belongs to an output block")
        if "output" in s.attrs and "from" not in s.attrs and not any(t.doc == s.doc and t.attrs.get("expect") == s.name for t in every):
            problems.append(f"{s.where}: an output block that no snippet expects (expect={s.name})")
    return every, problems


def groups(snippets: list[Snippet]) -> dict[tuple[str, str], list[Snippet]]:
    result: dict[tuple[str, str], list[Snippet]] = {}
    for s in snippets:
        if (s.run or "file" in s.attrs or "from" in s.attrs) and "after" not in s.attrs:
            result.setdefault((s.doc, s.group), []).append(s)
    for s in snippets:  # each after=NAME right behind NAME
        if "after" in s.attrs and (s.doc, s.group) in result:
            members = result[(s.doc, s.group)]
            index = next((i for i, m in enumerate(members) if m.name == s.attrs["after"]), None)
            if index is None:
                raise SystemExit(f"{s.where}: after={s.attrs['after']}: no snippet of that name in group {s.group}")
            members.insert(index + 1, s)
    return result


def group_id(doc: str, group: str) -> str:
    return f"{doc_stem(doc)}.{group}"


# ---------------------------------------------------------------------------------------------
# C++ programs


def cpp_program(s: Snippet, every: list[Snippet]) -> str:
    """The program of a C++ snippet: as written, or (wrap=main) its statements in main(), or
    (wrap=fields) its designated initializers in a haptic::ClientConfig; helpers=NAME puts what
    precedes main() in the program NAME (its includes and functions) in front."""
    wrap = s.attrs.get("wrap")
    if wrap is None:
        return f"#line {s.line + 1} \"{s.doc}\"\n" + s.code
    prelude = "#include <haptic/haptic.hpp>\n"
    if "helpers" in s.attrs:
        helper = next(t for t in every if t.doc == s.doc and t.name == s.attrs["helpers"])
        prelude = (f"#line {helper.line + 1} \"{helper.doc}\"\n" +
                   helper.code.split("\nint main(", 1)[0] + "\n")
    if wrap == "fields":
        return (prelude + "\nint main() {\n  const haptic::ClientConfig config{\n"
                f"#line {s.line + 1} \"{s.doc}\"\n" + s.code + "  };\n  return config.server_address.empty();\n}\n")
    includes = [ln for ln in s.code.splitlines() if ln.startswith("#include")]
    body = [ln if not ln.startswith("#include") else "" for ln in s.code.splitlines()]
    return (prelude + "\n".join(includes) + "\n#include <exception>\n#include <iostream>\n\n"
            "int main() {\n  try {\n"
            f"#line {s.line + 1} \"{s.doc}\"\n" + "\n".join(body) +
            "\n  } catch (const std::exception& error) {\n"
            "    std::cerr << \"snippet: \" << error.what() << \"\\n\";\n    return 1;\n  }\n}\n")


# ---------------------------------------------------------------------------------------------
# Comparing output


def compare(expected: str, actual: str, what: str) -> None:
    """Raises SnippetError unless `actual` shows `expected` (with `...` gaps)."""
    want = [ln.rstrip() for ln in expected.rstrip("\n").split("\n")]
    got = [LOG_STAMP.sub("", ln.rstrip()) for ln in actual.rstrip("\n").split("\n")]
    chunks, chunk = [], []
    for ln in want:
        if ln.strip() == "...":
            chunks.append(chunk)
            chunk = []
        else:
            chunk.append(ln)
    chunks.append(chunk)
    position = 0
    for index, chunk in enumerate(chunks):
        if not chunk:
            continue
        anchored_start = index == 0
        anchored_end = index == len(chunks) - 1
        candidates = [0] if anchored_start else range(position, len(got) - len(chunk) + 1)
        if anchored_end and not anchored_start:
            candidates = [len(got) - len(chunk)] if len(got) - len(chunk) >= position else []
        found = next((c for c in candidates if got[c:c + len(chunk)] == chunk), None)
        if found is None:
            near = closest(chunk, got, position)
            raise SnippetError(
                f"{what}: these lines of the doc's output are not in the output it printed"
                f"{' (at its start)' if anchored_start else ''}{' (at its end)' if anchored_end else ''}:\n"
                + "\n".join("  doc:  " + ln for ln in chunk) + "\n"
                + (f"the nearest it printed:\n" + "\n".join("  ran:  " + ln for ln in near) + "\n" if near else "")
                + "whole output:\n" + actual)
        position = found + len(chunk)


def closest(chunk: list[str], got: list[str], start: int) -> list[str]:
    head = chunk[0].split()[:1]
    for i in range(start, len(got)):
        if got[i].split()[:1] == head:
            return got[i:i + len(chunk)]
    return []


def python_expectations(code: str) -> list[str]:
    out = []
    for ln in code.splitlines():
        if "print(" in ln and "#" in ln:
            out.append(re.sub(r"\s+\(.*\)$", "", ln.split("#", 1)[1].strip()))
    return out


def sh_comment_expectations(code: str) -> list[str]:
    out, seen_command = [], False
    for ln in code.splitlines():
        stripped = ln.strip()
        if stripped.startswith("#"):
            if seen_command:
                out.append(stripped[1:].strip())
        elif stripped:
            seen_command = True
    return out


# ---------------------------------------------------------------------------------------------
# The sandbox


def enter_sandbox(scratch: Path) -> None:
    """Called in the child of `unshare --mount --net`: private overlays, loopback, hosts."""
    def sh(*cmd: str) -> None:
        subprocess.run(cmd, check=True)
    sh("mount", "--make-rprivate", "/")
    for top in ("/etc", "/usr", "/opt", "/var"):
        upper, work = scratch / "overlay" / top[1:] / "upper", scratch / "overlay" / top[1:] / "work"
        upper.mkdir(parents=True)
        work.mkdir(parents=True)
        sh("mount", "-t", "overlay", "overlay", "-o",
           f"lowerdir={top},upperdir={upper},workdir={work}", top)
    for fresh in ("/root", "/home"):
        sh("mount", "-t", "tmpfs", "-o", "mode=0755", "tmpfs", fresh)
    sh("ip", "link", "set", "lo", "up")
    with open("/etc/hosts", "a", encoding="utf-8") as hosts:
        for address, names in EXAMPLE_HOSTS.items():
            if not address.startswith("127."):
                sh("ip", "addr", "add", f"{address}/32", "dev", "lo")
            hosts.write(f"{address} {' '.join(names)}\n")


class Group:
    def __init__(self, source: Path, build: Path, programs: Path, snippets: list[Snippet],
                 every: list[Snippet], preload: str | None = None):
        self.source, self.build, self.programs, self.snippets = source, build, programs, snippets
        self.every = every  # all the documents' blocks: where an expect= names its output block
        self.scratch = Path(tempfile.mkdtemp(prefix="doc-snippet-"))
        self.work = self.scratch / "work"
        self.work.mkdir()
        for entry in source.iterdir():
            if entry.name not in ("build",) and not entry.name.startswith("build-"):
                (self.work / entry.name).symlink_to(entry)
        (self.work / "build").symlink_to(build)
        self.state = self.scratch / "shell-state"
        self.state.write_text(f"cd {shlex.quote(str(self.work))}\n")
        self.servers: list[tuple[subprocess.Popen, Path, str]] = []
        self.python_done: list[Snippet] = []
        self.env = dict(os.environ, HOME="/root", PYTHONDONTWRITEBYTECODE="1")
        self.env.pop("CDPATH", None)
        # Python snippets see the build's package, as docs/python.md's first command does.
        # Under the sanitizers the module needs their runtime loaded first: Python snippets, and
        # shell snippets that start Python, get it preloaded (leak checking off, as for pytest).
        sanitizer = {"LD_PRELOAD": preload, "ASAN_OPTIONS": "detect_leaks=0:halt_on_error=1"} if preload else {}
        self.python_env = dict(self.env, PYTHONPATH=str(self.work / "build" / "python"), **sanitizer)
        self.python_shell_env = dict(self.env, **sanitizer)

    # -- servers
    def start_server(self, command: str, user: str | None, ready: str) -> None:
        log = self.scratch / f"server-{len(self.servers)}.log"
        argv = ["bash", "-c", f"exec {command}"]
        if user:
            argv = ["runuser", "-u", user, "--"] + argv
        process = subprocess.Popen(argv, cwd=self.work, env=self.env, stdout=open(log, "wb"),
                                   stderr=subprocess.STDOUT, start_new_session=True)
        self.servers.append((process, log, command))
        host, _, port = ready.rpartition(":")
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            if process.poll() is not None:
                raise SnippetError(f"the server `{command}` exited with status {process.returncode} "
                                   f"before it served {ready}:\n{log.read_text(errors='replace')}")
            try:
                with socket.create_connection((host, int(port)), timeout=0.5):
                    return
            except OSError:
                time.sleep(0.1)
        raise SnippetError(f"the server `{command}` did not accept connections at {ready} within 60 s")

    def stop_servers(self) -> str:
        logs = ""
        for process, log, command in reversed(self.servers):
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGTERM)
                try:
                    process.wait(timeout=15)
                except subprocess.TimeoutExpired:
                    os.killpg(process.pid, signal.SIGKILL)
                    process.wait()
            logs += f"--- server `{command}` (exit {process.returncode}):\n{log.read_text(errors='replace')}"
        self.servers.clear()
        return logs

    # -- running
    def shell(self, script: str, timeout: float, what: str, env: dict | None = None) -> str:
        """Runs `script` in bash with the group's shell state; returns its output (stdout+stderr)."""
        wrapped = (f"source {shlex.quote(str(self.state))}\nset -eo pipefail\n{script}\n"
                   f"{{ echo \"cd $(printf %q \"$PWD\")\"; echo \"umask $(umask)\"; export -p; }} "
                   f"> {shlex.quote(str(self.state))}.next\n")
        result = self.execute(["bash", "-c", wrapped], timeout, what, env)
        Path(f"{self.state}.next").replace(self.state)
        return result

    def execute(self, argv: list[str], timeout: float, what: str, env: dict | None = None) -> str:
        try:
            done = subprocess.run(argv, cwd=self.work, env=env or self.env, text=True,
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=timeout)
        except subprocess.TimeoutExpired as expired:
            out = expired.stdout or ""
            raise SnippetError(f"{what}: still running after {timeout:.0f} s; its output so far:\n"
                               f"{out if isinstance(out, str) else out.decode(errors='replace')}")
        if done.returncode != 0:
            raise SnippetError(f"{what}: exit status {done.returncode}; its output:\n{done.stdout}")
        return done.stdout

    def streamed_lines(self, s: Snippet, seconds: float) -> str:
        output = ""
        for raw in s.code.splitlines():
            line = raw.strip()
            if not line or line.startswith("#"):
                continue
            # A line that ends carries its exports and working directory to the next, as in shell().
            script = (f"source {shlex.quote(str(self.state))}\nset -eo pipefail\n{line}\n"
                      f"{{ echo \"cd $(printf %q \"$PWD\")\"; echo \"umask $(umask)\"; export -p; }} "
                      f"> {shlex.quote(str(self.state))}.next\n")
            process = subprocess.Popen(["bash", "-c", script], cwd=self.work, env=self.env, text=True,
                                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                       start_new_session=True)
            # The window counts from the line's first output, not from its start: on a loaded
            # machine a TLS connection alone may take longer than the window.
            first_output, exited = read_until_quiet(process, seconds, FIRST_OUTPUT_WITHIN_S)
            if exited:
                out, _ = process.communicate()
                out = first_output + out
                interrupted = False
            else:
                os.killpg(process.pid, signal.SIGINT)
                try:
                    out, _ = process.communicate(timeout=10)
                except subprocess.TimeoutExpired:
                    os.killpg(process.pid, signal.SIGKILL)
                    out, _ = process.communicate()
                    raise SnippetError(f"{s.where}: `{line}` did not stop on SIGINT within 10 s:\n"
                                       f"{first_output + out}")
                out = first_output + out
                interrupted = True
            if process.returncode != 0:
                raise SnippetError(f"{s.where}: `{line}` exit status {process.returncode}"
                                   f"{' after SIGINT' if interrupted else ''}; its output:\n{out}")
            if not interrupted:
                Path(f"{self.state}.next").replace(self.state)
            if interrupted and not out.strip():
                raise SnippetError(f"{s.where}: `{line}` printed nothing in {FIRST_OUTPUT_WITHIN_S:.0f} s")
            output += out
        return output

    def run_snippet(self, s: Snippet) -> None:
        timeout = float(s.attrs.get("timeout", "120"))
        if "before" in s.attrs:
            self.shell(s.attrs["before"], timeout, f"{s.where}: the step before it (`{s.attrs['before']}`)")
        if "file" in s.attrs:
            path = self.work / s.attrs["file"]  # an absolute path stays as it is
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(s.code, encoding="utf-8")
            if s.attrs.get("check") == "config":
                hapticd = self.build / "server" / "app" / "hapticd"
                self.execute([str(hapticd), "--config", str(path), "--print-config"], timeout,
                             f"{s.where}: hapticd --config {path} --print-config")
        if "server" in s.attrs:
            self.start_server(s.attrs["server"], s.attrs.get("server-user"),
                              s.attrs.get("server-ready", "127.0.0.1:50051"))
        if "from" in s.attrs:
            command = s.attrs["from"]
            done = subprocess.run(["bash", "-c", f"source {shlex.quote(str(self.state))}\n{command}"],
                                  cwd=self.work, env=self.env, text=True, stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, timeout=timeout)
            if "status" in s.attrs and done.returncode != int(s.attrs["status"]):
                raise SnippetError(f"{s.where}: `{command}` exit status {done.returncode}, the doc says "
                                   f"{s.attrs['status']}; its output:\n{done.stdout}")
            compare("...\n" + s.code + "...\n", done.stdout, f"{s.where} against `{command}`")
            print(f"ok   {s.where}\n{indent(head(done.stdout))}", flush=True)
            return
        output = ""
        if not s.run:
            print(f"ok   {s.where}", flush=True)
            return
        if s.run == "sh":
            if "stream" in s.attrs:
                output = self.streamed_lines(s, float(s.attrs["stream"]))
            else:
                prefix = f"cd {shlex.quote(str(self.work))}\n" if "in-tree" in s.attrs else ""
                starts_python = re.search(r"\bpython3?\b|/bin/python", s.code) is not None
                output = self.shell(prefix + s.code, timeout, s.where,
                                    self.python_shell_env if starts_python else None)
            for m in re.finditer(r"#\s*expect:\s*(.+)$", s.code, re.MULTILINE):
                if m.group(1).strip() not in output:
                    raise SnippetError(f"{s.where}: the doc expects '{m.group(1).strip()}' in the "
                                       f"output; it printed:\n{output}")
            if s.attrs.get("expect") == "comments":
                compare_lines(sh_comment_expectations(s.code), output, s.where)
        elif s.run == "python":
            before = "".join(p.code for p in self.python_done)
            marker = "__doc_snippet_output_starts__"
            script = before + f"\nprint({marker!r})\n" + s.code
            full = self.execute(["/usr/bin/python3", "-c", script], timeout, s.where, env=self.python_env)
            output = full.split(marker + "\n", 1)[-1]
            self.python_done.append(s)
            if s.attrs.get("expect") == "comments":
                compare_lines(python_expectations(s.code), output, s.where)
        elif s.run == "cpp":
            program = self.programs / f"doc_snippet_{s.program_id}"
            output = self.execute([str(program)], timeout, f"{s.where} (built as {program.name})")
        expect = s.attrs.get("expect")
        if expect and expect != "comments":
            target = next(t for t in self.every if t.doc == s.doc and t.name == expect)
            wanted = target.code
            if "expect-lines" in s.attrs:
                first, _, last = s.attrs["expect-lines"].partition("-")
                wanted = "...\n" + "".join(wanted.splitlines(True)[int(first) - 1:int(last)]) + "...\n"
            compare(wanted, output, f"{s.where} against {target.where}")
        print(f"ok   {s.where}" + (f"\n{indent(head(output))}" if output.strip() else ""), flush=True)

    def run(self) -> int:
        try:
            for s in self.snippets:
                self.run_snippet(s)
        except SnippetError as error:
            print(f"FAIL {error}", flush=True)
            print(self.stop_servers(), flush=True)
            return 1
        except BaseException:
            self.stop_servers()
            raise
        logs = self.stop_servers()
        if logs:
            print(logs, flush=True)
        return 0


FIRST_OUTPUT_WITHIN_S = 60.0


def read_until_quiet(process: subprocess.Popen, window_s: float, first_within_s: float) -> tuple[str, bool]:
    """Reads `process`'s stdout until it exits or `window_s` has passed since its first output
    (at most `first_within_s` waiting for that). Returns what was read and whether it exited."""
    fd = process.stdout.fileno()
    chunks: list[bytes] = []
    deadline = time.monotonic() + first_within_s
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            return b"".join(chunks).decode(errors="replace"), False
        ready, _, _ = select.select([fd], [], [], left)
        if not ready:
            continue
        data = os.read(fd, 65536)
        if not data:
            return b"".join(chunks).decode(errors="replace"), True
        if not chunks:
            deadline = time.monotonic() + window_s
        chunks.append(data)


def compare_lines(expected: list[str], output: str, where: str) -> None:
    got = [LOG_STAMP.sub("", ln).strip() for ln in output.splitlines()]
    position = 0
    for line in expected:
        try:
            position = got.index(line, position) + 1
        except ValueError:
            raise SnippetError(f"{where}: the doc shows the output line\n  {line}\nwhich it did not print "
                               f"(in order); it printed:\n{output}") from None


PASSED_OUTPUT_LINES = 12


def head(text: str, lines: int = PASSED_OUTPUT_LINES) -> str:
    """The first lines of a passed snippet's output: a failure further on, printed whole, must
    stay near the top of the test's log, where a log's excerpt looks."""
    rows = text.rstrip("\n").split("\n")
    if len(rows) <= lines:
        return text
    return "\n".join(rows[:lines]) + f"\n... ({len(rows) - lines} more lines)"


def indent(text: str) -> str:
    return "\n".join("     | " + ln for ln in text.rstrip("\n").split("\n"))


# ---------------------------------------------------------------------------------------------


def main(argv: list[str]) -> int:
    if len(argv) < 3:
        print(__doc__)
        return 2
    command, source = argv[1], Path(argv[2]).resolve()
    snippets, problems = load(source)
    if command == "check":
        for p in problems:
            print(p)
        ran = sum(1 for s in snippets if s.run)
        print(f"{len(snippets)} blocks annotated in {len(documents(source))} documents: {ran} run, "
              f"{sum('output' in s.attrs for s in snippets)} outputs compared, "
              f"{sum('skip' in s.attrs for s in snippets)} not run (each with its reason), "
              f"{sum('shows' in s.attrs for s in snippets)} not code; {len(problems)} problems")
        return 1 if problems else 0
    # Problems elsewhere (doc.annotations names them) leave the well-formed groups runnable.
    if command == "list":
        for (doc, group), members in groups(snippets).items():
            # Installs write the build's install_manifest.txt: CMake runs those one at a time.
            installs = any("cmake --install" in m.code + m.attrs.get("before", "") for m in members)
            print(group_id(doc, group) + (":install" if installs else ""))
        return 0
    if command == "cpp-list":
        for s in snippets:
            if s.run == "cpp":
                print(f"{s.program_id}:{s.doc}")
        return 0
    if command == "extract":
        wanted, out = argv[3], Path(argv[4])
        s = next((s for s in snippets if s.run == "cpp" and s.program_id == wanted), None)
        if s is None:
            print(f"no C++ snippet {wanted}", file=sys.stderr)
            return 1
        out.write_text(cpp_program(s, snippets), encoding="utf-8")
        return 0
    if command in ("run", "_inside"):
        wanted = argv[3]
        options = dict(zip(argv[4::2], argv[5::2]))
        members = next((m for (doc, g), m in groups(snippets).items() if group_id(doc, g) == wanted), None)
        if members is None:
            print(f"no snippet group {wanted}", file=sys.stderr)
            return 1
        if command == "run":
            if os.geteuid() != 0 or not shutil.which("unshare"):
                print("skipped: the snippets run in a mount and network namespace of their own, "
                      "which needs root (CI runs as root)")
                return SKIP
            # Debian's interpreter: the sandbox's fresh /root hides an interpreter installed there.
            python = "/usr/bin/python3" if Path("/usr/bin/python3").exists() else sys.executable
            # A pid namespace too, whose first process dies with this one (--kill-child): a
            # timed-out test leaves no server behind in a namespace nobody can reach.
            return subprocess.call(["unshare", "--mount", "--net", "--pid", "--mount-proc", "--fork",
                                    "--kill-child", python,
                                    str(Path(__file__).resolve()), "_inside", str(source), wanted]
                                   + argv[4:])
        group = Group(source, Path(options["--build"]).resolve(), Path(options["--programs"]).resolve(),
                      members, snippets, options.get("--python-preload"))
        enter_sandbox(group.scratch)
        try:
            return group.run()
        finally:
            shutil.rmtree(group.scratch, ignore_errors=True)
    print(__doc__)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
