#!/usr/bin/env bash
# Builds the hapticd image with podman, runs it, and connects the host's touch_wall to it.
# Exits 77 (reported by ctest as skipped, never passed) when podman or a base image is unavailable.
# Usage: container_test.sh <source-dir> <touch_wall binary>
set -euo pipefail
source_dir="$1"
touch_wall="$2"

if ! command -v podman >/dev/null 2>&1; then
  echo "SKIP: podman is not installed (apt-get install podman runc debootstrap)"
  exit 77
fi
podman_opts=(--runtime runc)
run_opts=(--ulimit nofile=1024:1024 --ulimit nproc=1024:1024)

# No registry is reachable here: make the Debian 12 base image locally once, with debootstrap.
base=localhost/hapticd-base:bookworm
if ! podman "${podman_opts[@]}" image exists "$base"; then
  if ! command -v debootstrap >/dev/null 2>&1 || [ "$(id -u)" -ne 0 ]; then
    echo "SKIP: no base image $base and cannot debootstrap one (needs root and debootstrap)"
    exit 77
  fi
  rootfs=$(mktemp -d)
  echo "making base image $base with debootstrap (about a minute)"
  debootstrap --variant=minbase bookworm "$rootfs" >/dev/null
  tar -C "$rootfs" -c . | podman "${podman_opts[@]}" import - "$base" >/dev/null
  rm -rf "$rootfs"
fi

echo "building image hapticd:test"
podman "${podman_opts[@]}" build "${run_opts[@]}" -q -f "$source_dir/docker/Dockerfile" \
  --build-arg BASE_IMAGE="$base" -t localhost/hapticd:test "$source_dir" >/dev/null

work=$(mktemp -d)
chmod 777 "$work"
container=""
cleanup() {
  [ -n "$container" ] && podman "${podman_opts[@]}" rm -f "$container" >/dev/null 2>&1 || true
  rm -rf "$work"
}
trap cleanup EXIT

# Host networking with ephemeral loopback ports: no fixed port can collide with anything else.
container=$(podman "${podman_opts[@]}" run -d "${run_opts[@]}" --network host -v "$work:/run/hapticd" \
  localhost/hapticd:test --grpc-address 127.0.0.1:0 --udp-port 0 --ready-file /run/hapticd/ready.json)
for _ in $(seq 1 200); do
  [ -f "$work/ready.json" ] && break
  sleep 0.1
done
if [ ! -f "$work/ready.json" ]; then
  echo "FAIL: the container did not become ready"; podman "${podman_opts[@]}" logs "$container"; exit 1
fi
grpc_port=$(sed -n 's/.*"grpc_port": *\([0-9]*\).*/\1/p' "$work/ready.json")
user=$(podman "${podman_opts[@]}" exec "$container" id -un)
[ "$user" = hapticd ] || { echo "FAIL: container runs as '$user', not hapticd"; exit 1; }

echo "running touch_wall against the container on port $grpc_port"
output=$("$touch_wall" "127.0.0.1:$grpc_port")
echo "$output"
# The wall must push back: some printed force above 1 N.
echo "$output" | awk '$4+0 > 1.0 {found=1} END {exit !found}' || { echo "FAIL: no force from the wall"; exit 1; }
echo "PASS: container served touch_wall"
