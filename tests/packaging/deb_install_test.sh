#!/usr/bin/env bash
# The Debian packages (packaging/debian/CPack.cmake, docs/packaging.md) from this build, installed
# with apt into a clean Debian 12 container (the debootstrap base image of the container test),
# used there and purged: deb_install_inside.sh is what runs inside. Prints each package's size and
# dependencies, the install's key lines and how long it took.
# podman, runc and debootstrap missing fail it; HAPTIC_SKIP_CONTAINER=1 skips it (exit 77):
# tests/container/base_image.sh.
# Usage: deb_install_test.sh SOURCE_DIR BUILD_DIR [--python]
#   --python: the build has the Python module, so python3-hapticd is made and tested too (an
#   empty third argument: it has not).
set -euo pipefail
if [ $# -lt 2 ] || [ $# -gt 4 ]; then
  echo "usage: deb_install_test.sh SOURCE_DIR BUILD_DIR [--python] [--csharp]"; exit 2
fi
python=""
csharp=""
for option in "${@:3}"; do
  case "$option" in
    --python) python=--python ;;
    --csharp) csharp=--csharp ;;
    "") ;;
    *) echo "deb_install_test.sh: unknown argument '$option' (expected --python, --csharp or nothing)"; exit 2 ;;
  esac
done
if [ ! -f "$2/CPackConfig.cmake" ]; then
  echo "deb_install_test.sh: '$2' is not a configured build of hapticd (no CPackConfig.cmake)"; exit 2
fi
source_dir="$1"
build_dir="$2"
started=$(date +%s)

# podman_opts, run_opts and the Debian 12 base image $base (made once with debootstrap).
source "$source_dir/tests/container/base_image.sh"
for tool in cpack dpkg-deb dpkg-shlibdeps; do
  command -v "$tool" >/dev/null 2>&1 ||
    { echo "FAIL: $tool is missing (scripts/setup installs cmake, dpkg-dev and file)"; exit 1; }
done

work=$(mktemp -d)
container=""
cleanup() {
  [ -n "$container" ] && podman "${podman_opts[@]}" rm -f -t 0 "$container" >/dev/null 2>&1 || true
  rm -rf "$work"
}
trap cleanup EXIT

echo "== cpack -G DEB in $build_dir (prefix /usr)"
if ! (cd "$build_dir" && cpack -G DEB -B "$work/packages") >"$work/cpack.log" 2>&1; then
  cat "$work/cpack.log"; echo "FAIL: cpack failed"; exit 1
fi
packages=(hapticd hapticd-tools libhaptic-c1 libhapticd-dev)
[ "$python" = --python ] && packages+=(python3-hapticd)
[ "$csharp" = --csharp ] && packages+=(libhapticd-cil)
mkdir -p "$work/test/debs"
printf '%-16s %10s %14s  %s\n' package "file KiB" "installed KiB" depends
for package in "${packages[@]}"; do
  deb=$(find "$work/packages" -maxdepth 1 -name "${package}_*.deb")
  [ -n "$deb" ] && [ "$(echo "$deb" | wc -l)" = 1 ] ||
    { echo "FAIL: cpack made no single ${package}_*.deb:"; ls "$work/packages"; exit 1; }
  depends=$(dpkg-deb -f "$deb" Depends)
  printf '%-16s %10s %14s  %s\n' "$package" "$(( $(stat -c %s "$deb") / 1024 ))" \
    "$(dpkg-deb -f "$deb" Installed-Size)" "$depends"
  # dpkg-shlibdeps filled in the shared libraries' packages (libc6 at least).
  case "$package" in
    libhapticd-dev) grep -q 'libhaptic-c1 (= ' <<<"$depends" ||
                      { echo "FAIL: libhapticd-dev does not depend on its libhaptic-c1"; exit 1; } ;;
    libhapticd-cil) grep -q 'mono-runtime' <<<"$depends" && [ "$(dpkg-deb -f "$deb" Architecture)" = all ] ||
                      { echo "FAIL: libhapticd-cil is not Architecture: all depending on mono-runtime"; exit 1; } ;;
    *) grep -q 'libc6' <<<"$depends" ||
         { echo "FAIL: $package has no shared library dependencies (dpkg-shlibdeps)"; exit 1; } ;;
  esac
  cp "$deb" "$work/test/debs/"
done
echo "packages made in $(( $(date +%s) - started )) s"
# What an archive would check first: lintian, no error on any package (its warnings printed).
command -v lintian >/dev/null 2>&1 ||
  { echo "FAIL: lintian is missing (scripts/setup installs it)"; exit 1; }
if ! lintian --fail-on error --tag-display-limit 0 "$work"/test/debs/*.deb >"$work/lintian.log" 2>&1; then
  grep -v 'root privileges' "$work/lintian.log"; echo "FAIL: lintian reports errors"; exit 1
fi
echo "lintian: no error; $(grep -c '^W: ' "$work/lintian.log" || true) warnings:"
grep '^W: ' "$work/lintian.log" | sed 's/^/  /' || true

cp "$source_dir/tests/packaging/deb_install_inside.sh" "$work/test/"
cp -r "$source_dir/tests/install/consumer" "$work/test/consumer"
# Host networking: apt reaches Debian's mirror, and the servers inside bind ephemeral loopback ports.
container=$(podman "${podman_opts[@]}" run -d "${run_opts[@]}" --network host "$base" sleep infinity)
podman "${podman_opts[@]}" cp "$work/test" "$container:/tmp/hapticd-test"
podman "${podman_opts[@]}" exec "$container" bash /tmp/hapticd-test/deb_install_inside.sh ${python:+--python} ${csharp:+--csharp}
echo "PASS: the packages install with apt in a clean Debian 12, serve, build and purge cleanly \
($(( $(date +%s) - started )) s)"
