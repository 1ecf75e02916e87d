#!/usr/bin/python3
"""Every entry of scripts/mutants.list still applies: its file exists and its `from` text occurs
exactly once there. The mutation run is not in the default test run (it takes minutes), so a
change that rewrites a checked line would otherwise leave its entry stale until the next run
refused it. Usage: mutants_list_applies.py SOURCE_DIR
"""
import re
import sys

source_dir = sys.argv[1]
text = open(f"{source_dir}/scripts/mutants.list", encoding="utf-8").read()
problems, entries = [], 0
for block in re.split(r"\n\s*\n", text):
    fields = dict(re.findall(r"^(id|file|from|to|tests): (.*)$", block, flags=re.M))
    if "id" not in fields:
        continue
    entries += 1
    try:
        content = open(f"{source_dir}/{fields['file']}", encoding="utf-8").read()
    except OSError as error:
        problems.append(f"{fields['id']}: {fields.get('file')}: {error.strerror}")
        continue
    count = content.count(fields.get("from", "\0"))
    if count != 1:
        problems.append(f"{fields['id']}: its 'from' text occurs {count} times in {fields['file']}, not once")
print(f"scripts/mutants.list: {entries} entries")
if problems:
    print("FAIL: entries that no longer apply (rewrite them with the line as it is now):")
    print("\n".join("  " + p for p in problems))
    sys.exit(1)
