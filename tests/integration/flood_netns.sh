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
source "$(dirname "${BASH_SOURCE[0]}")/../support/netns_bridge.sh"

binary="$1"
skip() { echo "flood_netns: skipped: $*"; exit 77; }

netns_bridge_check

tag=$$
switch_ns="hflood-br-$tag"
server_ns="hflood-s-$tag"
workstation_ns="hflood-w-$tag"
flood_namespaces=()
for i in 1 2 3 4 5 6; do flood_namespaces+=("hflood-$i-$tag"); done

cleanup() { netns_bridge_cleanup "$server_ns" "$workstation_ns" "${flood_namespaces[@]}" "$switch_ns"; }
trap cleanup EXIT

netns_bridge_make "$switch_ns"
# attach NAMESPACE ADDRESS INDEX: a namespace with ADDRESS/24 on a veth to the bridge.
attach() { netns_bridge_attach "$switch_ns" "$1" "$2" "hf$3-$tag" "hfb$3-$tag"; }

attach "$server_ns" 10.79.0.1 0
attach "$workstation_ns" 10.79.0.8 8
for i in 1 2 3 4 5 6; do attach "${flood_namespaces[$((i - 1))]}" "10.79.0.$((10 + i))" "$i"; done

ip netns exec "$workstation_ns" env HAPTIC_FLOOD_SERVER_NS="$server_ns" \
  HAPTIC_FLOOD_NAMESPACES="${flood_namespaces[*]}" "$binary"
