#!/usr/bin/python3
"""Fails naming every #include that goes against the layering (docs/architecture.md): each
library under server/ may include only itself and the layers listed for it, so the graph stays
one-way (no lab -> app/net, no runtime -> schema, nothing -> app); and driver/ (the ABI and the
drivers) and sdk/ (the client SDK, which builds without the server) include nothing of server/.
Usage: layers.py SOURCE_DIR"""
import pathlib
import re
import sys

# Library -> the server libraries it may include besides itself. "haptic/..." (the wire, proto and
# SDK headers) is allowed everywhere.
ALLOWED = {
    "engine": set(),
    "runtime": {"engine"},
    "schema": {"engine"},
    "config": {"engine", "runtime", "schema", "federation"},
    "recording": {"engine", "runtime", "schema"},
    "net": {"engine", "runtime", "schema", "recording"},
    "federation": {"engine", "runtime"},
    "app": {"engine", "runtime", "schema", "config", "recording", "net", "federation"},
    "lab": {"engine", "runtime", "schema", "config"},
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([a-z_]+)/')

source = pathlib.Path(sys.argv[1])
server = source / "server"


def includes(folder, suffixes=(".hpp", ".cpp", ".h", ".c")):
    """(path, line number, first folder) of each #include "folder/..." in the sources under `folder`."""
    for path in sorted(folder.rglob("*")):
        if path.suffix not in suffixes:
            continue
        for number, line in enumerate(path.read_text().splitlines(), 1):
            match = INCLUDE.match(line)
            if match:
                yield path, number, match.group(1)


# Where a library may include only some headers of a layer it may include: config takes the
# federation's options alone (federation/options.hpp is free of DDS), so that it, and haptic-lab
# through it, do not link Cyclone DDS.
ONLY = {("config", "federation"): {"federation/options.hpp"}}
HEADER = re.compile(r'^\s*#\s*include\s+"([^"]+)"')

bad, checked = [], 0
for library, allowed in ALLOWED.items():
    for path, number, target in includes(server / library):
        checked += 1
        if (library, target) in ONLY:
            header = HEADER.match(path.read_text().splitlines()[number - 1]).group(1)
            if header not in ONLY[(library, target)]:
                bad.append(f"{path.relative_to(server)}:{number}: {library} includes {header} "
                           f"(of {target}/ it may include only {', '.join(sorted(ONLY[(library, target)]))})")
            continue
        if target in (library, "haptic") or target in allowed:
            continue
        bad.append(f"{path.relative_to(server)}:{number}: {library} includes {target}/ "
                   f"(allowed: {', '.join(sorted(allowed | {library})) or 'itself'})")
# Outside server/: what may be included by "dir/..." from each tree (its own folders, the public
# "haptic/" headers); a server library's name is a back edge.
OUTSIDE = {"driver": {"haptic", "common"}, "sdk": {"haptic"}}
for tree, allowed in OUTSIDE.items():
    for path, number, target in includes(source / tree):
        checked += 1
        if target in ALLOWED:
            bad.append(f"{path.relative_to(source)}:{number}: {tree}/ includes the server's "
                       f"{target}/ (it must build without the server)")
        elif target not in allowed:
            bad.append(f"{path.relative_to(source)}:{number}: {tree}/ includes {target}/ "
                       f"(allowed: {', '.join(sorted(allowed))})")
unknown = sorted(p.name for p in server.iterdir() if p.is_dir() and p.name not in ALLOWED)
for line in bad:
    print(line)
for name in unknown:
    print(f"server/{name}/: a library this check does not know; add it to ALLOWED")
print(f"{checked} includes checked, {len(bad)} against the layering")
sys.exit(1 if bad or unknown or checked == 0 else 0)
