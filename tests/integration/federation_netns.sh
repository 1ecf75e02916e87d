#!/usr/bin/env bash
# Three hapticd sites over real Cyclone DDS between network namespaces, for the federation's
# shared-scene and liveliness test (tests/integration/federation_netns_test.cpp): each site a
# namespace with one address on a bridge, and the test's clients in a fourth.
#
#   hfed-a  10.82.0.1  hapticd, site "site-a"
#   hfed-b  10.82.0.2  hapticd, site "site-b"
#   hfed-c  10.82.0.3  hapticd, site "site-c" (killed and restarted by the test)
#   hfed-w  10.82.0.8  the test binary: it starts each hapticd in its namespace, and its clients
#
# Usage: federation_netns.sh FEDERATION_NETNS_TEST_BINARY
# Exit 77 (ctest: skipped) where it cannot run: not root, no ip, no network namespaces. Everything
# it makes is removed on exit. Traffic stays inside these namespaces.
set -euo pipefail

binary="$1"
skip() { echo "federation_netns: skipped: $*"; exit 77; }

[ "$(id -u)" -eq 0 ] || skip "needs root (network namespaces)"
command -v ip >/dev/null || skip "needs ip (iproute2)"

tag=$$
switch_ns="hfed-br-$tag"
site_namespaces=("hfed-a-$tag" "hfed-b-$tag" "hfed-c-$tag")
site_addresses=(10.82.0.1 10.82.0.2 10.82.0.3)
workstation_ns="hfed-w-$tag"

cleanup() {
  for ns in "${site_namespaces[@]}" "$workstation_ns" "$switch_ns"; do
    ip netns del "$ns" 2>/dev/null || true
  done
}
trap cleanup EXIT

ip netns add "$switch_ns" 2>/dev/null || skip "cannot make a network namespace"
ip -n "$switch_ns" link add br0 type bridge 2>/dev/null || skip "cannot make a bridge"
ip -n "$switch_ns" link set br0 up

# attach NAMESPACE ADDRESS INDEX: a namespace with ADDRESS/24 on a veth to the bridge.
attach() {
  local ns="$1" address="$2" index="$3"
  ip netns add "$ns"
  ip link add "hfd$index-$tag" type veth peer name "hfdb$index-$tag" || skip "cannot make a veth pair"
  ip link set "hfd$index-$tag" netns "$ns"
  ip link set "hfdb$index-$tag" netns "$switch_ns"
  ip -n "$switch_ns" link set "hfdb$index-$tag" master br0
  ip -n "$switch_ns" link set "hfdb$index-$tag" up
  ip -n "$ns" link set lo up
  ip -n "$ns" addr add "$address/24" dev "hfd$index-$tag"
  ip -n "$ns" link set "hfd$index-$tag" up
}

for i in 0 1 2; do attach "${site_namespaces[$i]}" "${site_addresses[$i]}" "$i"; done
attach "$workstation_ns" 10.82.0.8 8

ip netns exec "$workstation_ns" env HAPTIC_FEDERATION_NAMESPACES="${site_namespaces[*]}" \
  HAPTIC_FEDERATION_ADDRESSES="${site_addresses[*]}" "$binary"
