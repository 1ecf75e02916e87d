#!/usr/bin/env bash
# The federation's tool-topic latency between sites in network namespaces (federation_latency_bench.cpp):
# up to eight sites, each a namespace with one address on a bridge, every site publishing one tool
# at 1 kHz and receiving all the others'. Per round and site count, plain UDP between the same
# namespaces first (the floor), then the tool topic over Cyclone DDS; a line per configuration,
# then the table with the DDS/UDP ratios and the targets. No netem: the bridge as it is.
#
#   hfedlat-0 .. hfedlat-7  10.81.0.10 .. 10.81.0.17  the sites
#
# Usage: federation_latency_netns.sh BENCH_BINARY [--seconds S] [--rounds R] [--sites "2 8"]
#                                    [--transports "udp dds"] [--fifo PRIORITY]
#   --seconds: measured per configuration (default 3); --rounds: times through all (default 2);
#   --transports: udp (the floor), dds (taken in a listener), dds-waitset (taken in a thread a
#   waitset wakes); the first should be udp, the others' ratios are to it; --fifo: every site's
#   process (its threads and Cyclone's) SCHED_FIFO at PRIORITY, as a real-time loop would run,
#   so that this host's other work delays the senders and receivers less.
# Exit 77 (ctest: skipped) where it cannot run: not root, no ip, no network namespaces. Everything
# it makes is removed on exit. Traffic stays inside these namespaces.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../support/netns_bridge.sh"

skip() { echo "federation_latency: skipped: $*"; exit 77; }
[ $# -ge 1 ] || { echo "usage: $0 BENCH_BINARY [--seconds S] [--rounds R] [--sites \"2 8\"] [--transports \"udp dds\"] [--fifo PRIORITY]" >&2; exit 2; }
binary="$1"
shift
seconds=3
rounds=2
site_counts="2 8"
transports="udp dds"
fifo=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds="$2"; shift 2 ;;
    --rounds) rounds="$2"; shift 2 ;;
    --sites) site_counts="$2"; shift 2 ;;
    --transports) transports="$2"; shift 2 ;;
    --fifo) fifo=(chrt -f "$2"); shift 2 ;;
    *) echo "federation_latency: unknown argument $1" >&2; exit 2 ;;
  esac
done

netns_bridge_check
if [ ${#fifo[@]} -gt 0 ]; then
  chrt -f 1 true 2>/dev/null || skip "cannot run SCHED_FIFO (--fifo)"
  echo "federation_latency: every site's process SCHED_FIFO, priority ${fifo[2]}"
fi

most=0
for n in $site_counts; do [ "$n" -gt "$most" ] && most="$n"; done
[ "$most" -ge 2 ] && [ "$most" -le 8 ] || { echo "federation_latency: --sites: 2 to 8 each" >&2; exit 2; }

tag=$$
switch_ns="hfedlat-br-$tag"
namespaces=()
addresses=()
for ((i = 0; i < most; i++)); do
  namespaces+=("hfedlat-$i-$tag")
  addresses+=("10.81.0.$((10 + i))")
done
work="$(mktemp -d)"
site_pids=()

cleanup() {
  for pid in "${site_pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  netns_bridge_cleanup "${namespaces[@]}" "$switch_ns"
  rm -rf "$work"
}
trap cleanup EXIT

netns_bridge_make "$switch_ns"
for ((i = 0; i < most; i++)); do
  netns_bridge_attach "$switch_ns" "${namespaces[$i]}" "${addresses[$i]}" "hfl$i-$tag" "hflb$i-$tag"
done

# A configuration: every site's process in its namespace, measuring from one common start time
# (CLOCK_MONOTONIC, shared by the namespaces) after time to start and, for DDS, to discover.
run_configuration() {
  local round="$1" transport="$2" sites="$3"
  local dir="$work/r$round-$transport-$sites"
  local list margin_ms start status=0
  mkdir "$dir"
  list="$(IFS=,; echo "${addresses[*]:0:$sites}")"
  margin_ms=$([ "$transport" = udp ] && echo 500 || echo 2500)
  start=$(($("$binary" clock) + margin_ms * 1000000))
  echo "federation_latency: round $round, $sites sites over $transport: ${seconds} s at 1 kHz each ..."
  site_pids=()
  for ((i = 0; i < sites; i++)); do
    ip netns exec "${namespaces[$i]}" "${fifo[@]}" "$binary" site --transport "$transport" --index "$i" \
      --addresses "$list" --start-ns "$start" --seconds "$seconds" --round "$round" \
      --out "$dir/site-$i.txt" &
    site_pids+=($!)
  done
  for pid in "${site_pids[@]}"; do wait "$pid" || status=1; done
  site_pids=()
  [ "$status" -eq 0 ] || { echo "federation_latency: a site failed (round $round, $sites over $transport)" >&2; exit 1; }
  "$binary" summary "$dir" || true
  dirs+=("$dir")
}

dirs=()
for ((round = 1; round <= rounds; round++)); do
  for sites in $site_counts; do
    for transport in $transports; do run_configuration "$round" "$transport" "$sites"; done
  done
done
"$binary" report "${dirs[@]}"
