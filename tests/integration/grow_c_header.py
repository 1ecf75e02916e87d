#!/usr/bin/python3
"""Writes haptic_c.h as a later version of it would be: every struct that starts with `uint32_t
size;` (the structs that may grow) gets a field appended, `grown_by_test`. The C API growth test
builds libhaptic_c from it (HAPTIC_C_TEST_GROWN) and runs a program built against the real,
version 1 header against that library. Usage: grow_c_header.py IN_HEADER OUT_HEADER
"""
import re
import sys

source, target = sys.argv[1:3]
lines = open(source, encoding="utf-8").read().split("\n")
out = []
grown = 0
open_struct = None  # the name of the sized struct being copied, until its closing line
for index, line in enumerate(lines):
    opening = re.match(r"typedef struct (\w+) \{", line)
    if opening and index + 1 < len(lines) and re.match(r"\s*uint32_t size;", lines[index + 1]):
        open_struct = opening.group(1)
    if open_struct and line.startswith("} " + open_struct + ";"):
        out.append("  double grown_by_test[3]; /* appended by tests/integration/grow_c_header.py */")
        grown += 1
        open_struct = None
    out.append(line)
if grown < 10:
    sys.exit(f"grow_c_header.py: only {grown} sized structs found in {source}: has the header's form changed?")
open(target, "w", encoding="utf-8").write("\n".join(out))
print(f"grow_c_header.py: {grown} structs grown")
