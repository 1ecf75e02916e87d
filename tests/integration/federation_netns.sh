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
source "$(dirname "${BASH_SOURCE[0]}")/../support/netns_bridge.sh"

binary="$1"
skip() { echo "federation_netns: skipped: $*"; exit 77; }

netns_bridge_check

tag=$$
switch_ns="hfed-br-$tag"
site_namespaces=("hfed-a-$tag" "hfed-b-$tag" "hfed-c-$tag")
site_addresses=(10.82.0.1 10.82.0.2 10.82.0.3)
workstation_ns="hfed-w-$tag"

cleanup() { netns_bridge_cleanup "${site_namespaces[@]}" "$workstation_ns" "$switch_ns"; }
trap cleanup EXIT

netns_bridge_make "$switch_ns"
# attach NAMESPACE ADDRESS INDEX: a namespace with ADDRESS/24 on a veth to the bridge.
attach() { netns_bridge_attach "$switch_ns" "$1" "$2" "hfd$3-$tag" "hfdb$3-$tag"; }

for i in 0 1 2; do attach "${site_namespaces[$i]}" "${site_addresses[$i]}" "$i"; done
attach "$workstation_ns" 10.82.0.8 8

ip netns exec "$workstation_ns" env HAPTIC_FEDERATION_NAMESPACES="${site_namespaces[*]}" \
  HAPTIC_FEDERATION_ADDRESSES="${site_addresses[*]}" "$binary"
