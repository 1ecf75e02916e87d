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
grep -qx "RestartPreventExitStatus=2" "$unit" || { echo "FAIL: a configuration error would restart"; exit 1; }
# verify reads the unit as systemd would (settings, ExecStart's binary); any complaint fails it.
if ! out="$(systemd-analyze verify "$unit" 2>&1)" || [ -n "$out" ]; then
  echo "FAIL: systemd-analyze verify $unit:"; echo "$out"; exit 1
fi

root="$work/root"
mkdir -p "$root/etc"
systemd-sysusers --root="$root" "$prefix/lib/sysusers.d/hapticd.conf"
grep -q '^hapticd:x:[0-9]*:[0-9]*:hapticd networked haptic server:/:/usr/sbin/nologin$' "$root/etc/passwd" ||
  { echo "FAIL: sysusers.d made no hapticd account:"; cat "$root/etc/passwd"; exit 1; }
systemd-tmpfiles --create --root="$root" "$prefix/lib/tmpfiles.d/hapticd.conf"
[ "$(stat -c '%a' "$root/run/hapticd")" = 1777 ] ||
  { echo "FAIL: /run/hapticd is not 1777: $(stat -c '%a' "$root/run/hapticd")"; exit 1; }
echo "systemd files: the unit verifies, the account and /run/hapticd are made"
