#!/bin/bash
# The part of deb_install_test.sh that runs inside a clean Debian 12 container, as root, with the
# packages in /tmp/hapticd-test/debs: installs them with apt (their Debian dependencies from the
# mirror), checks what the hapticd package set up, runs a lockstep hapticd as the hapticd account
# and touch_wall, hapticctl, the Python example and the C example (compiled against the installed
# header and library) against it, builds tests/install/consumer with find_package(hapticd), then
# purges the packages and checks that nothing of theirs is left; then installs hapticd again where
# systemd is installed (not running), enables its unit and purges it.
# With --csharp, libhapticd-cil's touch_wall under Debian's Mono against a server's HTTP face too.
# Usage: deb_install_inside.sh [--python] [--csharp]
set -euo pipefail
test_dir=/tmp/hapticd-test
python=0
csharp=0
for option in "$@"; do
  case "$option" in
    --python) python=1 ;;
    --csharp) csharp=1 ;;
    *) echo "deb_install_inside.sh: unknown argument '$option' (expected --python, --csharp or nothing)"; exit 2 ;;
  esac
done
export DEBIAN_FRONTEND=noninteractive
fail() { echo "FAIL: $*"; exit 1; }
step() { echo "== $*"; }
packages=(hapticd hapticd-tools libhaptic-c1 libhapticd-dev)
[ "$python" = 1 ] && packages+=(python3-hapticd)
[ "$csharp" = 1 ] && packages+=(libhapticd-cil)
started=$(date +%s)

step "apt-get install ${packages[*]} (from the .deb files, --no-install-recommends)"
apt-get update -qq
if ! apt-get install -y --no-install-recommends "$test_dir"/debs/*.deb >"$test_dir/install.log" 2>&1; then
  cat "$test_dir/install.log"; fail "apt-get install of the packages failed"
fi
# The transcript's key lines: how much came from Debian, and what the packages' scripts said.
grep -E '^[0-9]+ upgraded|^Need to get|^After this operation|^Setting up (hapticd|hapticd-tools|libhaptic|python3-hapticd)|^Processing triggers for libc-bin|[Ww]arning|[Ee]rror|useradd|Creating' \
  "$test_dir/install.log" || true
echo "installed in $(( $(date +%s) - started )) s"
for package in "${packages[@]}"; do
  # (grep reads a here-string, not a pipe: with pipefail a grep -q that stops reading early would
  # fail the pipe)
  grep -qx "install ok installed" <<<"$(dpkg-query -W -f '${Status}' "$package")" ||
    fail "$package is not installed: $(dpkg-query -W -f '${Status}' "$package" 2>&1)"
  dpkg -L "$package" >"$test_dir/files.$package"
done

step "what the hapticd package set up"
grep -q ':/:/usr/sbin/nologin$' <<<"$(getent passwd hapticd)" ||
  fail "no hapticd system account with no login: '$(getent passwd hapticd || true)'"
[ "$(stat -c %a /run/hapticd)" = 1777 ] || fail "/run/hapticd is not 1777: $(stat -c %a /run/hapticd)"
grep -q '^ /etc/hapticd/config.json ' <<<"$(dpkg-query -W -f '${Conffiles}\n' hapticd)" ||
  fail "/etc/hapticd/config.json is not a conffile of hapticd"
grep -qx 'ExecStart=/usr/bin/hapticd --config /etc/hapticd/config.json' /usr/lib/systemd/system/hapticd.service ||
  fail "the unit does not start /usr/bin/hapticd --config /etc/hapticd/config.json"
hapticd --config /etc/hapticd/config.json --print-config >/dev/null ||
  fail "hapticd refuses the configuration the package installs"
[ -f /usr/share/hapticd/web/index.html ] || fail "no viewer page in /usr/share/hapticd/web"
# hapticd finds the packaged drivers where it was built to look (<libdir>/hapticd under /usr).
hapticd --list-devices >"$test_dir/devices.txt" 2>&1 || { cat "$test_dir/devices.txt"; fail "hapticd --list-devices failed"; }
grep -Eq '^/usr/lib/([a-z0-9_-]+/)?hapticd/point_mass_driver\.so \(driver ABI [0-9]+\): 1 device' "$test_dir/devices.txt" ||
  { cat "$test_dir/devices.txt"; fail "hapticd does not find the packaged example driver"; }
echo "account: $(getent passwd hapticd)"
echo "conffile /etc/hapticd/config.json; unit /usr/lib/systemd/system/hapticd.service (not enabled)"
grep point_mass "$test_dir/devices.txt"

# A lockstep hapticd as the hapticd account, on ephemeral loopback ports, found through its ready
# file; each example gets a fresh one (lockstep is exact from a fresh start).
server_pid=""
port=""
start_server() {  # [--http-api 0]: http_port is the HTTP face's then
  rm -f /run/hapticd/ready.json
  setpriv --reuid=hapticd --regid=hapticd --init-groups -- hapticd --lockstep \
    --grpc-address 127.0.0.1:0 --udp-port 0 --ready-file /run/hapticd/ready.json "$@" \
    >"$test_dir/hapticd.log" 2>&1 &
  server_pid=$!
  for _ in $(seq 1 200); do
    [ -s /run/hapticd/ready.json ] && break
    kill -0 "$server_pid" 2>/dev/null || { cat "$test_dir/hapticd.log"; fail "hapticd exited at start"; }
    sleep 0.1
  done
  [ -s /run/hapticd/ready.json ] || { cat "$test_dir/hapticd.log"; fail "hapticd did not become ready"; }
  port=$(sed -n 's/.*"grpc_port": *\([0-9]*\).*/\1/p' /run/hapticd/ready.json)
  [ -n "$port" ] || fail "no grpc_port in the ready file: $(cat /run/hapticd/ready.json)"
  http_port=$(sed -n 's/.*"http_port": *\([0-9]*\).*/\1/p' /run/hapticd/ready.json)
}
stop_server() {
  kill -INT "$server_pid"
  wait "$server_pid" || { cat "$test_dir/hapticd.log"; fail "hapticd exited with status $? on SIGINT"; }
  server_pid=""
  rm -f /run/hapticd/ready.json  # the test's, not the package's
}
rows() { grep -E '^ *[0-9]' "$1" || true; }

step "hapticd (as hapticd), touch_wall and hapticctl"
start_server
[ "$(stat -c %U "/proc/$server_pid")" = hapticd ] || fail "hapticd does not run as hapticd"
touch_wall "127.0.0.1:$port" --lockstep >"$test_dir/touch_wall.txt" || fail "touch_wall failed"
tail -2 "$test_dir/touch_wall.txt"
# Lockstep is exact: the wall, the field and the hand settle where the README says.
grep -q "^  2.960      -10.00    -1.311      1.738  yes$" "$test_dir/touch_wall.txt" ||
  fail "touch_wall did not settle at z = -1.311 mm, 1.738 N"
hapticctl --server "127.0.0.1:$port" status >"$test_dir/status.txt" || fail "hapticctl status failed"
hapticctl --server "127.0.0.1:$port" sessions >"$test_dir/sessions.txt" || fail "hapticctl sessions failed"
grep -E '^(loop|sessions) ' "$test_dir/status.txt"
# touch_wall stepped 3 s of 1 kHz ticks and closed its session: the one open is hapticctl's own
# (marked * in its table).
ticks=$(sed -n 's/^loop *\([0-9]*\) ticks.*/\1/p' "$test_dir/status.txt")
[ -n "$ticks" ] && [ "$ticks" -ge 3000 ] || fail "hapticctl status shows '${ticks}' ticks, not 3 s of them"
grep -q '^sessions  1 open' "$test_dir/status.txt" ||
  fail "hapticctl status: $(grep '^sessions' "$test_dir/status.txt"), not its own session alone"
grep -Eq '\* +hapticctl' "$test_dir/sessions.txt" && ! grep -q touch_wall "$test_dir/sessions.txt" ||
  { cat "$test_dir/sessions.txt"; fail "hapticctl sessions does not list its own session alone"; }
stop_server

if [ "$python" = 1 ]; then
  step "the Python example with Debian's python3"
  start_server
  python3 /usr/share/doc/python3-hapticd/examples/touch_wall.py "127.0.0.1:$port" --lockstep \
    >"$test_dir/touch_wall_py.txt" || fail "touch_wall.py failed"
  stop_server
  diff <(rows "$test_dir/touch_wall.txt") <(rows "$test_dir/touch_wall_py.txt") ||
    fail "touch_wall.py does not print touch_wall's rows"
  echo "touch_wall.py: the same $(rows "$test_dir/touch_wall_py.txt" | wc -l) rows as touch_wall"
fi

if [ "$csharp" = 1 ]; then
  step "the C# example under Debian's Mono, against the HTTP face"
  start_server --http-api 0
  [ -n "$http_port" ] || fail "no http_port in the ready file: $(cat /run/hapticd/ready.json)"
  MONO_PATH=/usr/lib/cli/hapticd mono /usr/share/doc/libhapticd-cil/examples/touch_wall.exe \
    "127.0.0.1:$http_port" --lockstep >"$test_dir/touch_wall_cs.txt" || fail "the C# touch_wall failed"
  stop_server
  diff <(rows "$test_dir/touch_wall.txt") <(rows "$test_dir/touch_wall_cs.txt") ||
    fail "the C# touch_wall does not print touch_wall's rows"
  echo "touch_wall.exe: the same $(rows "$test_dir/touch_wall_cs.txt" | wc -l) rows as touch_wall"
fi

step "against libhapticd-dev: the C example (cc -lhaptic_c) and find_package(hapticd)"
toolchain_started=$(date +%s)
apt-get install -y -qq --no-install-recommends gcc g++ libc6-dev cmake make >"$test_dir/toolchain.log" 2>&1 ||
  { cat "$test_dir/toolchain.log"; fail "could not install the compilers and cmake"; }
echo "compilers and cmake installed in $(( $(date +%s) - toolchain_started )) s"
cc -std=c99 -Wall -Wextra -Werror -o "$test_dir/touch_wall_c" \
  /usr/share/doc/libhapticd-dev/examples/touch_wall.c -lhaptic_c -lm || fail "the C example does not build"
grep -Eq 'libhaptic_c\.so\.1 => (/usr)?/lib/' <<<"$(ldd "$test_dir/touch_wall_c")" ||
  fail "the C example does not load the installed libhaptic_c.so.1: $(ldd "$test_dir/touch_wall_c" | grep haptic)"
start_server
"$test_dir/touch_wall_c" "127.0.0.1:$port" --lockstep >"$test_dir/touch_wall_c.txt" || fail "touch_wall_c failed"
stop_server
diff <(rows "$test_dir/touch_wall.txt") <(rows "$test_dir/touch_wall_c.txt") ||
  fail "the C example does not print touch_wall's rows"
echo "touch_wall.c: the same $(rows "$test_dir/touch_wall_c.txt" | wc -l) rows as touch_wall"
cmake -S "$test_dir/consumer" -B "$test_dir/consumer-build" >"$test_dir/consumer.log" 2>&1 &&
  cmake --build "$test_dir/consumer-build" -j2 >>"$test_dir/consumer.log" 2>&1 ||
  { cat "$test_dir/consumer.log"; fail "the find_package(hapticd) consumer does not build"; }
"$test_dir/consumer-build/consumer" || fail "the consumer did not get its ConnectionError"

# A lock file a server left behind (hapticd claims a CPU with one): purge takes it too.
touch /run/hapticd/hapticd-loop-cpu0.lock
step "apt-get purge ${packages[*]}"
apt-get purge -y "${packages[@]}" >"$test_dir/purge.log" 2>&1 || { cat "$test_dir/purge.log"; fail "apt-get purge failed"; }
grep -E '^Removing|^Purging|[Ww]arning|[Ee]rror' "$test_dir/purge.log" || true
for package in "${packages[@]}"; do
  if dpkg-query -W -f '${Status}' "$package" >/dev/null 2>&1; then
    fail "$package is still known to dpkg: $(dpkg-query -W -f '${Status}' "$package")"
  fi
done
# Every path the packages held is gone, but folders other installed packages still hold.
left=""
for package in "${packages[@]}"; do
  while IFS= read -r path; do
    [ "$path" = "/." ] && continue
    [ -e "$path" ] || [ -L "$path" ] || continue
    if [ -d "$path" ] && [ ! -L "$path" ] && dpkg -S "$path" >/dev/null 2>&1; then continue; fi
    left+="$path ($package)"$'\n'
  done <"$test_dir/files.$package"
done
[ -z "$left" ] || fail "left after purge:"$'\n'"$left"
[ ! -e /etc/hapticd ] || fail "/etc/hapticd is left: $(ls -A /etc/hapticd)"
[ ! -e /run/hapticd ] || fail "/run/hapticd is left: $(ls -A /run/hapticd)"
hash -r  # bash remembers where it found the programs it ran
! command -v hapticd >/dev/null || fail "hapticd is still on the PATH: $(command -v hapticd)"
# The account stays, as Debian's packages leave system accounts (docs/packaging.md, Removing).
getent passwd hapticd >/dev/null || fail "the hapticd account went with the package"
echo "purged: no file, folder or configuration of the packages is left; the hapticd account stays"

# Where systemd is installed (as on a server; here not running, as in a chroot): the account and
# /run/hapticd come from the package's sysusers.d and tmpfiles.d files, and a unit the
# administrator enabled is disabled on removal, leaving no link behind.
step "hapticd where systemd is installed: systemd-sysusers, systemd-tmpfiles, enable, purge"
userdel hapticd
systemd_started=$(date +%s)
apt-get install -y -qq --no-install-recommends systemd >"$test_dir/systemd.log" 2>&1 ||
  { cat "$test_dir/systemd.log"; fail "could not install systemd"; }
apt-get install -y -qq --no-install-recommends "$test_dir"/debs/hapticd_*.deb >"$test_dir/install2.log" 2>&1 ||
  { cat "$test_dir/install2.log"; fail "hapticd does not install where systemd is"; }
echo "systemd and hapticd installed in $(( $(date +%s) - systemd_started )) s"
grep -q '^hapticd:x:[0-9]*:[0-9]*:hapticd networked haptic server:/:/usr/sbin/nologin$' <<<"$(getent passwd hapticd)" ||
  fail "systemd-sysusers made no hapticd account: '$(getent passwd hapticd || true)'"
[ "$(stat -c %a /run/hapticd)" = 1777 ] || fail "systemd-tmpfiles did not make /run/hapticd 1777"
wants=/etc/systemd/system/multi-user.target.wants/hapticd.service
systemctl enable hapticd.service >/dev/null 2>&1 || fail "systemctl enable hapticd.service failed"
[ -L "$wants" ] || fail "systemctl enable made no $wants"
apt-get purge -y hapticd >"$test_dir/purge2.log" 2>&1 || { cat "$test_dir/purge2.log"; fail "apt-get purge hapticd failed"; }
[ ! -e "$wants" ] && [ ! -L "$wants" ] || fail "the enabled unit's link $wants is left after purge"
[ ! -e /usr/lib/systemd/system/hapticd.service ] || fail "the unit is left after purge"
[ ! -e /etc/hapticd ] || fail "/etc/hapticd is left after purge"
echo "account by systemd-sysusers, /run/hapticd by systemd-tmpfiles; enabled, then purged with no link left"
echo "inside the container: $(( $(date +%s) - started )) s"
