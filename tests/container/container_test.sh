#!/usr/bin/env bash
# Builds the hapticd image with podman from this build's binaries (docker/Dockerfile with
# BINARIES=prebuilt: the runtime stage users get, without compiling everything a second time),
# runs it in lockstep, checks its user, that it holds hapticd alone and that the runtime's health
# status (the image's HEALTHCHECK) turns healthy, and drives it with the host's touch_wall in
# lockstep; then runs each container command the documentation gives, as typed, and checks that
# nothing listens beyond loopback (documented_commands.py).
# podman, runc and debootstrap missing fail it; HAPTIC_SKIP_CONTAINER=1 skips it (exit 77):
# base_image.sh.
# Usage: container_test.sh <source-dir> <hapticd binary> <touch_wall binary>
set -euo pipefail
source_dir="$1"
hapticd="$2"
touch_wall="$3"

# podman_opts, run_opts and the Debian 12 base image $base (made once with debootstrap).
source "$source_dir/tests/container/base_image.sh"

work=$(mktemp -d)
chmod 777 "$work"
container=""
cleanup() {
  [ -n "$container" ] && podman "${podman_opts[@]}" rm -f "$container" >/dev/null 2>&1 || true
  rm -rf "$work"
}
trap cleanup EXIT

# A small build context: the Dockerfile, the container configuration and this build's binaries.
context="$work/context"
mkdir -p "$context/docker/prebuilt"
cp "$source_dir/docker/Dockerfile" "$source_dir/docker/hapticd-container.json" "$context/docker/"
cp "$hapticd" "$context/docker/prebuilt/"
echo "building image hapticd:test"
# Rebuilding leaves the previous image and its stages untagged: those this build left go again.
dangling_before=$(podman "${podman_opts[@]}" images -q --filter dangling=true | sort)
# --format docker: the OCI format has no HEALTHCHECK, so podman's default would drop it.
podman "${podman_opts[@]}" build "${run_opts[@]}" --format docker -q -f "$context/docker/Dockerfile" \
  --build-arg BASE_IMAGE="$base" --build-arg BINARIES=prebuilt -t localhost/hapticd:test \
  "$context" >/dev/null
dangling_after=$(podman "${podman_opts[@]}" images -q --filter dangling=true | sort)
stale=$(comm -13 <(echo "$dangling_before") <(echo "$dangling_after") | grep . || true)
[ -z "$stale" ] || podman "${podman_opts[@]}" rmi $stale >/dev/null 2>&1 || true

health_command=$(podman "${podman_opts[@]}" image inspect --format '{{json .Config.Healthcheck.Test}}' \
  localhost/hapticd:test)
echo "image health check: $health_command"
echo "$health_command" | grep -q -- '--health-check' \
  || { echo "FAIL: the image has no HEALTHCHECK running hapticd --health-check"; exit 1; }
# The runtime stage holds hapticd alone: no example, tool or build output beside it.
installed=$(podman "${podman_opts[@]}" run --rm "${run_opts[@]}" --entrypoint /bin/ls \
  localhost/hapticd:test /usr/local/bin | tr '\n' ' ')
[ "$installed" = "hapticd " ] \
  || { echo "FAIL: /usr/local/bin in the image holds '$installed', not hapticd alone"; exit 1; }

# Host networking with ephemeral loopback ports: no fixed port can collide with anything else.
mkdir -p "$work/run"
chmod 777 "$work/run"
container=$(podman "${podman_opts[@]}" run -d "${run_opts[@]}" --network host -v "$work/run:/run/hapticd" \
  localhost/hapticd:test --lockstep --grpc-address 127.0.0.1:0 --udp-port 0)
for _ in $(seq 1 200); do
  [ -f "$work/run/ready.json" ] && break
  sleep 0.1
done
if [ ! -f "$work/run/ready.json" ]; then
  echo "FAIL: the container did not become ready"; podman "${podman_opts[@]}" logs "$container"; exit 1
fi
grpc_port=$(sed -n 's/.*"grpc_port": *\([0-9]*\).*/\1/p' "$work/run/ready.json")
user=$(podman "${podman_opts[@]}" exec "$container" id -un)
[ "$user" = hapticd ] || { echo "FAIL: container runs as '$user', not hapticd"; exit 1; }
# The runtime's own health check (the image's HEALTHCHECK, run now rather than on its 10 s timer):
# it must find the server on its ephemeral port through the ready file, and report it healthy.
podman "${podman_opts[@]}" healthcheck run "$container" \
  || { echo "FAIL: the image's health check does not see the server serving"; exit 1; }
status=$(podman "${podman_opts[@]}" inspect --format '{{.State.Health.Status}}' "$container")
echo "health status: $status"
[ "$status" = healthy ] || { echo "FAIL: health status '$status', not healthy"; exit 1; }

echo "running touch_wall against the container on port $grpc_port, in lockstep"
output=$("$touch_wall" "127.0.0.1:$grpc_port" --lockstep)
echo "$output" | tail -5
# Lockstep is exact: the wall, the field and the hand settle where the README says.
echo "$output" | grep -q "^  2.960      -10.00    -1.311      1.738  yes$" \
  || { echo "FAIL: touch_wall did not settle at z = -1.311 mm, 1.738 N"; exit 1; }
echo "PASS: the container served touch_wall in lockstep"
podman "${podman_opts[@]}" rm -f "$container" >/dev/null 2>&1 || true
container=""

# Every documented `docker run` / `podman run`, as typed, against this image: what listens where.
/usr/bin/python3 "$source_dir/tests/container/documented_commands.py" "$source_dir" \
  localhost/hapticd:test "$hapticd" "${run_opts[@]}"
