#!/usr/bin/env bash
# A small LAN of network namespaces for the descriptor-flood test (tests/integration/
# flood_test.cpp): hapticd's host, one lab workstation, and six flooding hosts, each a namespace
# with one address on a bridge. No netem: the flood needs addresses, not impairment.
#
#   hflood-s  10.79.0.1  hapticd (mutual TLS, tokens, 256 descriptors)
#   hflood-w  10.79.0.8  the test binary: a lab client, and the flood's sockets made in the others
#   hflood-1 .. hflood-6  10.79.0.11 .. 10.79.0.16  the flooding hosts
#
# Usage: flood_netns.sh FLOOD_TEST_BINARY
# Exit 77 (ctest: skipped) where it cannot run: not root, no ip, no network namespaces. Everything
# it makes is removed on exit. Traffic stays inside these namespaces.
set -euo pipefail

binary="$1"
skip() { echo "flood_netns: skipped: $*"; exit 77; }

[ "$(id -u)" -eq 0 ] || skip "needs root (network namespaces)"
command -v ip >/dev/null || skip "needs ip (iproute2)"

tag=$$
switch_ns="hflood-br-$tag"
server_ns="hflood-s-$tag"
workstation_ns="hflood-w-$tag"
flood_namespaces=()
for i in 1 2 3 4 5 6; do flood_namespaces+=("hflood-$i-$tag"); done

cleanup() {
  for ns in "$server_ns" "$workstation_ns" "${flood_namespaces[@]}" "$switch_ns"; do
    ip netns del "$ns" 2>/dev/null || true
  done
}
trap cleanup EXIT

ip netns add "$switch_ns" 2>/dev/null || skip "cannot make a network namespace"
ip -n "$switch_ns" link add br0 type bridge
ip -n "$switch_ns" link set br0 up

# attach NAMESPACE ADDRESS INDEX: a namespace with ADDRESS/24 on a veth to the bridge.
attach() {
  local ns="$1" address="$2" index="$3"
  ip netns add "$ns"
  ip link add "hf$index-$tag" type veth peer name "hfb$index-$tag"
  ip link set "hf$index-$tag" netns "$ns"
  ip link set "hfb$index-$tag" netns "$switch_ns"
  ip -n "$switch_ns" link set "hfb$index-$tag" master br0
  ip -n "$switch_ns" link set "hfb$index-$tag" up
  ip -n "$ns" link set lo up
  ip -n "$ns" addr add "$address/24" dev "hf$index-$tag"
  ip -n "$ns" link set "hf$index-$tag" up
}

attach "$server_ns" 10.79.0.1 0
attach "$workstation_ns" 10.79.0.8 8
for i in 1 2 3 4 5 6; do attach "${flood_namespaces[$((i - 1))]}" "10.79.0.$((10 + i))" "$i"; done

ip netns exec "$workstation_ns" env HAPTIC_FLOOD_SERVER_NS="$server_ns" \
  HAPTIC_FLOOD_NAMESPACES="${flood_namespaces[*]}" "$binary"
