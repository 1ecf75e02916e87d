#!/usr/bin/env bash
# The systemd files `cmake --install` puts beside hapticd: installed into a fresh prefix, the unit
# passes `systemd-analyze verify` and names the installed binary, sysusers.d makes the hapticd
# account and tmpfiles.d the shared lock folder /run/hapticd (sticky, open to all), each inside a
# root folder of the test's own (--root), never the host's.
#
# Usage: systemd_test.sh BUILD_DIR
# Exit 77 (ctest: skipped) without systemd-analyze, systemd-sysusers or systemd-tmpfiles.
set -euo pipefail
build="$1"
for tool in systemd-analyze systemd-sysusers systemd-tmpfiles; do
  command -v "$tool" >/dev/null || { echo "systemd_test: skipped: no $tool"; exit 77; }
done
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
prefix="$work/prefix"
cmake --install "$build" --prefix "$prefix" >/dev/null

unit="$prefix/lib/systemd/system/hapticd.service"
[ -f "$unit" ] || { echo "FAIL: no $unit"; exit 1; }
grep -qx "ExecStart=$prefix/bin/hapticd --config /etc/hapticd/config.json" "$unit" ||
  { echo "FAIL: the unit does not start the installed binary:"; grep ExecStart "$unit"; exit 1; }
grep -qx "RuntimeDirectory=hapticd" "$unit" || { echo "FAIL: no RuntimeDirectory=hapticd"; exit 1; }
# Under a prefix other than /usr nothing reads <prefix>/etc/hapticd/config.json (the unit reads
# /etc's): the default configuration is an example to copy, under share.
[ ! -e "$prefix/etc/hapticd/config.json" ] ||
  { echo "FAIL: $prefix/etc/hapticd/config.json is installed, but the unit reads /etc/hapticd/config.json"; exit 1; }
"$prefix/bin/hapticd" --config "$prefix/share/hapticd/config.example.json" --print-config >/dev/null ||
  { echo "FAIL: no usable example configuration at $prefix/share/hapticd/config.example.json"; exit 1; }
grep -qx "RestartPreventExitStatus=2" "$unit" || { echo "FAIL: a configuration error would restart"; exit 1; }
# verify reads the unit as systemd would (settings, ExecStart's binary); any complaint fails it.
if ! out="$(systemd-analyze verify "$unit" 2>&1)" || [ -n "$out" ]; then
  echo "FAIL: systemd-analyze verify $unit:"; echo "$out"; exit 1
fi

# Hardened as systemd's own tools advise: `systemd-analyze security` scores the unit (6.2 MEDIUM
# before its hardening block; lower is better) and it must stay OK (at most 3.0).
exposure=$(systemd-analyze security --offline=true "$unit" 2>&1 | sed -n 's/.*Overall exposure level for hapticd.service: \([0-9.]*\).*/\1/p')
[ -n "$exposure" ] || { echo "FAIL: systemd-analyze security gave no score:"; systemd-analyze security --offline=true "$unit"; exit 1; }
echo "systemd-analyze security: exposure $exposure"
awk -v e="$exposure" 'BEGIN { exit !(e <= 3.0) }' ||
  { echo "FAIL: exposure $exposure above 3.0:"; systemd-analyze security --offline=true "$unit" | grep '✗'; exit 1; }

# Its system call filter refuses nothing the server calls: hapticd in real time, asking for
# SCHED_FIFO, CPU affinity and mlockall, answering a health check, traced with strace; every
# system call it made must be in what the unit's SystemCallFilter= lines allow.
if command -v strace >/dev/null; then
  printf '{"grpc_address": "127.0.0.1:0", "udp_port": 0, "status_period_s": 0, "real_time": {"use_fifo": true}}\n' \
    > "$work/rt.json"
  strace -f -qq -c -o "$work/strace.txt" "$prefix/bin/hapticd" --config "$work/rt.json" \
    --ready-file "$work/ready.json" >"$work/hapticd.log" 2>&1 &
  traced=$!
  for _ in $(seq 1 200); do [ -s "$work/ready.json" ] && break; sleep 0.1; done
  "$prefix/bin/hapticd" --health-check --ready-file "$work/ready.json" >/dev/null ||
    { kill "$traced"; cat "$work/hapticd.log"; echo "FAIL: the traced hapticd did not serve"; exit 1; }
  sleep 1
  pkill -TERM -f "$prefix/bin/hapticd --config $work/rt.json" || true
  wait "$traced" || true
  grep -E 'SCHED_FIFO|mlockall' "$work/hapticd.log" | sed 's/^\[[^]]*\] //' | head -3 || true
  /usr/bin/python3 - "$unit" "$work/strace.txt" <<'PY' || exit 1
import subprocess, sys
unit, trace = sys.argv[1:3]
def expand(name, seen=None):
    seen = set() if seen is None else seen
    if not name.startswith("@"):
        return {name}
    if name in seen:
        return set()
    seen.add(name)
    out = subprocess.run(["systemd-analyze", "syscall-filter", name], capture_output=True, text=True,
                         check=True).stdout
    calls = set()
    for line in out.splitlines()[1:]:
        word = line.strip().split()[0] if line.strip() else ""
        if word and not word.startswith("#"):
            calls |= expand(word, seen)
    return calls
allowed, denied = set(), set()
for line in open(unit):
    if line.startswith("SystemCallFilter="):
        value = line.split("=", 1)[1].strip()
        if value.startswith("~"):
            for group in value[1:].split():
                denied |= expand(group)
        else:
            for group in value.split():
                allowed |= expand(group)
used = set()
for line in open(trace):
    fields = line.split()
    if len(fields) >= 5 and fields[-1].replace("_", "").isalnum() and fields[-1] not in ("syscall", "total"):
        used.add(fields[-1])
refused = sorted(used - (allowed - denied))
print(f"system calls hapticd made: {len(used)}; allowed by the unit: {len(allowed - denied)}")
for needed in ("sched_setscheduler", "sched_setaffinity", "mlockall"):
    if needed not in used:
        print(f"note: hapticd did not call {needed} here")
if refused:
    print("FAIL: the unit's SystemCallFilter refuses what hapticd calls: " + ", ".join(refused))
    sys.exit(1)
PY
else
  echo "FAIL: strace is missing (scripts/setup installs it)"; exit 1
fi

root="$work/root"
mkdir -p "$root/etc"
systemd-sysusers --root="$root" "$prefix/lib/sysusers.d/hapticd.conf"
grep -q '^hapticd:x:[0-9]*:[0-9]*:hapticd networked haptic server:/:/usr/sbin/nologin$' "$root/etc/passwd" ||
  { echo "FAIL: sysusers.d made no hapticd account:"; cat "$root/etc/passwd"; exit 1; }
systemd-tmpfiles --create --root="$root" "$prefix/lib/tmpfiles.d/hapticd.conf"
[ "$(stat -c '%a' "$root/run/hapticd")" = 1777 ] ||
  { echo "FAIL: /run/hapticd is not 1777: $(stat -c '%a' "$root/run/hapticd")"; exit 1; }
echo "systemd files: the unit verifies and is hardened (exposure $exposure), its system call filter allows what hapticd calls, the account and /run/hapticd are made"
