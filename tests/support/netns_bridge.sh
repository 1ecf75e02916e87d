# A small LAN of network namespaces on one bridge, for the tests and benchmarks that need real
# addresses between processes (tests/integration/flood_netns.sh, federation_netns.sh,
# tests/bench/federation_latency_netns.sh). Sourced, not run: the sourcing script names the
# namespaces, interfaces and addresses, and defines skip MESSAGE (prints it and exits 77), which
# these functions call where the host cannot make what they need.

# netns_bridge_check: skips unless this runs as root with ip (iproute2).
netns_bridge_check() {
  [ "$(id -u)" -eq 0 ] || skip "needs root (network namespaces)"
  command -v ip >/dev/null || skip "needs ip (iproute2)"
}

# netns_bridge_make SWITCH_NS: a namespace holding the bridge br0, up.
netns_bridge_make() {
  local switch_ns="$1"
  ip netns add "$switch_ns" 2>/dev/null || skip "cannot make a network namespace"
  ip -n "$switch_ns" link add br0 type bridge 2>/dev/null || skip "cannot make a bridge"
  ip -n "$switch_ns" link set br0 up
}

# netns_bridge_attach SWITCH_NS NS ADDRESS VETH PEER: the namespace NS with ADDRESS/24 on VETH,
# whose other end PEER is on SWITCH_NS's bridge. Interface names: 15 characters at most.
netns_bridge_attach() {
  local switch_ns="$1" ns="$2" address="$3" veth="$4" peer="$5"
  ip netns add "$ns"
  ip link add "$veth" type veth peer name "$peer" || skip "cannot make a veth pair"
  ip link set "$veth" netns "$ns"
  ip link set "$peer" netns "$switch_ns"
  ip -n "$switch_ns" link set "$peer" master br0
  ip -n "$switch_ns" link set "$peer" up
  ip -n "$ns" link set lo up
  ip -n "$ns" addr add "$address/24" dev "$veth"
  ip -n "$ns" link set "$veth" up
}

# netns_bridge_cleanup NS...: deletes each namespace that exists (their veths go with them).
netns_bridge_cleanup() {
  local ns
  for ns in "$@"; do ip netns del "$ns" 2>/dev/null || true; done
}
