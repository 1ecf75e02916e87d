#!/usr/bin/env bash
# The Python package installed as docs/python.md ("Installing") says, with its commands: under the
# default prefix and /usr it lands in a site directory of the interpreter (seen through DESTDIR,
# as this test may not write there); under a prefix of its own (/opt/hapticd in the docs, a
# temporary one here) one .pth line in the user's site directory makes the interpreter import it;
# in a virtual environment made with `python3 -m venv --system-site-packages` it imports as
# installed, and with --mypy, mypy --strict checks python/tests/typed_example.py against the
# installed package there (its py.typed and stubs).
# Usage: python_install_test.sh <build-dir> <source-dir> <python> [--mypy]
#        (<python>: the interpreter the module is built for, /usr/bin/python3 in the docs)
set -euo pipefail
build_dir="$1"
source_dir="$2"
python="$3"
check_types="${4:-}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Nothing from the caller's environment may point at a package: only the documented steps.
unset PYTHONPATH PYTHONHOME PYTHONNOUSERSITE VIRTUAL_ENV
export PYTHONDONTWRITEBYTECODE=1
export PYTHONUSERBASE="$work/userbase"  # the user's site directory, in the sandbox
fail() { echo "FAIL: $*"; exit 1; }

# Imports hapticd with the interpreter $1 from a neutral directory and checks that it came from
# the directory $2 (HAPTIC_PYTHON_PRELOAD: the sanitizers' runtime a sanitized module needs).
imports_from() {
  (cd "$work" && LD_PRELOAD="${HAPTIC_PYTHON_PRELOAD:-}" ASAN_OPTIONS=detect_leaks=0 "$1" -c "
import sys, hapticd
assert hapticd.SphereSpec(radius=0.5).radius == 0.5
assert hapticd.__file__.startswith(sys.argv[1] + '/'), hapticd.__file__
print('imported', hapticd.__file__, 'API', hapticd.API_VERSION)" "$2")
}

# Where `cmake --install` put the package under DESTDIR for prefix $1; it must be one of the
# interpreter's own site directories.
for prefix in /usr/local /usr; do
  DESTDIR="$work/root" cmake --install "$build_dir" --component python --prefix "$prefix" >/dev/null
  package=$(cd "$work/root" && find ".$prefix" -name __init__.py -path '*/hapticd/*' | head -n 1)
  [ -n "$package" ] || fail "no package installed under $prefix"
  site=$(dirname "$(dirname "${package#.}")")
  "$python" -c "import site, sys; sys.exit(sys.argv[1] not in site.getsitepackages())" "$site" \
    || fail "$site (prefix $prefix) is not a site directory of $python"
  echo "prefix $prefix: $site, a site directory of $python"
  rm -rf "$work/root"
done

# A prefix of its own: the documented install and .pth line (/opt/hapticd is $work/opt here).
opt="$work/opt"
cmake --install "$build_dir" --prefix "$opt" >/dev/null
site="$opt/lib/python3.$("$python" -c 'import sys; print(sys.version_info.minor)')/site-packages"
for file in __init__.py _trajectory.py _native.pyi py.typed; do
  [ -f "$site/hapticd/$file" ] || fail "$site/hapticd/$file not installed"
done
compgen -G "$site/hapticd/_native*.so" >/dev/null || fail "the module is not in $site/hapticd"
mkdir -p "$("$python" -m site --user-site)" && echo "$site" > "$("$python" -m site --user-site)/hapticd.pth"
imports_from "$python" "$site" || fail "the package under a prefix of its own does not import"

# A virtual environment.
venv="$work/hapticd-venv"
"$python" -m venv --system-site-packages "$venv"
cmake --install "$build_dir" --component python --prefix "$venv" >/dev/null
imports_from "$venv/bin/python" "$venv/lib" || fail "the package in the virtual environment does not import"
if [ "$check_types" = --mypy ]; then
  printf '[mypy]\n' > "$work/mypy.ini"  # none of the user's
  (cd "$work" && "$python" -m mypy --strict --python-executable "$venv/bin/python" \
     --cache-dir "$work/mypy-cache" --config-file "$work/mypy.ini" \
     "$source_dir/python/tests/typed_example.py") \
    || fail "mypy --strict does not pass typed_example.py against the installed package"
fi
echo "python_install_test: ok"
