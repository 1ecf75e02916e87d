#!/usr/bin/env bash
# The simulated LAN with the kernel's netem: hapticd in a network namespace of its own, the test
# client in another, a veth pair between them shaped by netem on both ends (delay, jitter, loss,
# duplication, reordering, and 100 % loss for a pulled cable). Runs integration_lan_test's LAN
# tests there (tests/integration/lan_test.cpp, NetemNetwork).
#
# Usage: lan_netem.sh LAN_TEST_BINARY
# Exit 77 (ctest: skipped) where it cannot run: not root, no ip/tc, no network namespaces, or a
# kernel without sch_netem. Everything it makes is removed on exit.
set -euo pipefail

binary="$1"
skip() { echo "lan_netem: skipped: $*"; exit 77; }

[ "$(id -u)" -eq 0 ] || skip "needs root (network namespaces)"
command -v ip >/dev/null && command -v tc >/dev/null || skip "needs ip and tc (iproute2)"

server_ns="hapticd-lan-s-$$"
client_ns="hapticd-lan-c-$$"
server_dev="hlan-s-$$"
client_dev="hlan-c-$$"
server_ip=10.77.0.1
client_ip=10.77.0.2

cleanup() {
  ip netns del "$server_ns" 2>/dev/null || true
  ip netns del "$client_ns" 2>/dev/null || true
}
trap cleanup EXIT

ip netns add "$server_ns" 2>/dev/null || skip "cannot make a network namespace"
ip netns add "$client_ns"
ip link add "$client_dev" type veth peer name "$server_dev"
ip link set "$server_dev" netns "$server_ns"
ip link set "$client_dev" netns "$client_ns"
ip -n "$server_ns" addr add "$server_ip/24" dev "$server_dev"
ip -n "$client_ns" addr add "$client_ip/24" dev "$client_dev"
for ns in "$server_ns" "$client_ns"; do ip -n "$ns" link set lo up; done
ip -n "$server_ns" link set "$server_dev" up
ip -n "$client_ns" link set "$client_dev" up

if ! ip netns exec "$client_ns" tc qdisc add dev "$client_dev" root netem delay 1ms 2>/dev/null; then
  skip "this kernel has no netem qdisc (sch_netem)"
fi
ip netns exec "$server_ns" tc qdisc add dev "$server_dev" root netem delay 1ms

ip netns exec "$client_ns" env HAPTIC_LAN_NETNS="$server_ns" HAPTIC_LAN_SERVER_IP="$server_ip" \
  HAPTIC_LAN_CLIENT_DEV="$client_dev" HAPTIC_LAN_SERVER_DEV="$server_dev" \
  "$binary" --gtest_filter='Lan.*:Profiles/LanProfile.*'
