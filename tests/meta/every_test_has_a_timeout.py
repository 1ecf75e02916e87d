#!/usr/bin/python3
"""Fails naming every ctest test without a TIMEOUT property (ctest's default is 1,500 s: a test
that hangs would hold the whole suite, as one once held CI for 20 minutes).
Usage: every_test_has_a_timeout.py CTEST_COMMAND BUILD_DIR [MAX_SECONDS]"""
import json
import subprocess
import sys

ctest, build = sys.argv[1], sys.argv[2]
most = float(sys.argv[3]) if len(sys.argv) > 3 else 1800.0
listing = subprocess.run([ctest, "--test-dir", build, "--show-only=json-v1"],
                         capture_output=True, text=True, check=True)
tests = json.loads(listing.stdout)["tests"]
missing, too_long = [], []
for test in tests:
    timeout = next((p["value"] for p in test.get("properties", []) if p["name"] == "TIMEOUT"), None)
    if timeout is None:
        missing.append(test["name"])
    elif float(timeout) > most:
        too_long.append(f"{test['name']} ({timeout} s)")
for name in missing:
    print(f"no TIMEOUT: {name}")
for name in too_long:
    print(f"TIMEOUT over {most:g} s: {name}")
print(f"{len(tests)} tests, {len(missing)} without a timeout, {len(too_long)} over {most:g} s")
sys.exit(1 if missing or too_long or not tests else 0)
