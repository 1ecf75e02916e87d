# Sourced by the container tests (container_test.sh, tests/packaging/deb_install_test.sh): checks
# podman, runc and debootstrap and makes the Debian 12 base image once. No registry is reachable
# here, so the image is made locally with debootstrap (root needed the first time).
# scripts/setup installs the three tools, so a missing one is a failure, not a skip; exit 77
# (skipped) only when HAPTIC_SKIP_CONTAINER=1 says this machine cannot run containers at all.
# Sets: podman_opts (podman's own options), run_opts (for build and run), base (the image's name).
if [ "${HAPTIC_SKIP_CONTAINER:-0}" = 1 ]; then
  echo "SKIP: HAPTIC_SKIP_CONTAINER=1"
  exit 77
fi
for tool in podman runc debootstrap; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "FAIL: $tool is not installed (scripts/setup installs it: podman runc debootstrap)"
    exit 1
  fi
done
podman_opts=(--runtime runc)
run_opts=(--ulimit nofile=1024:1024 --ulimit nproc=1024:1024)

base=localhost/hapticd-base:bookworm
if ! podman "${podman_opts[@]}" image exists "$base"; then
  if [ "$(id -u)" -ne 0 ]; then
    echo "FAIL: no base image $base, and making one with debootstrap needs root"
    exit 1
  fi
  base_rootfs=$(mktemp -d)
  echo "making base image $base with debootstrap (about a minute)"
  debootstrap --variant=minbase bookworm "$base_rootfs" >/dev/null
  tar -C "$base_rootfs" -c . | podman "${podman_opts[@]}" import - "$base" >/dev/null
  rm -rf "$base_rootfs"
fi
