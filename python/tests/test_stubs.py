"""The type stubs (python/hapticd/_native.pyi, py.typed): up to date with the built module (stubgen
run again through python/generate_stubs.py), valid under `mypy --strict` with the package's own
Python, and used: a typed program passes mypy --strict and runs, and mistakes in another are
caught. Needs Debian's mypy (scripts/setup installs it); HAPTIC_BUILD_DIR names the build."""

import os
import pathlib
import subprocess
import sys

import pytest

pytest.importorskip("mypy", reason="needs mypy (apt install mypy)")

import typed_example  # noqa: E402

PYTHON_DIR = pathlib.Path(__file__).resolve().parents[1]
BUILD_DIR = pathlib.Path(os.environ.get("HAPTIC_BUILD_DIR", PYTHON_DIR.parent / "build"))


def mypy(tmp_path, *arguments):
    """mypy --strict on `arguments` (the package from PYTHONPATH, as the tests import it), with a
    cache of its own and no configuration file of this tree."""
    config = tmp_path / "mypy.ini"
    config.write_text("[mypy]\n")
    return subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--cache-dir", str(tmp_path / "mypy-cache"),
         "--config-file", str(config), *arguments],
        cwd=tmp_path, capture_output=True, text=True, timeout=180)


def test_the_checked_in_stubs_are_what_stubgen_makes_of_the_built_module():
    done = subprocess.run([sys.executable, str(PYTHON_DIR / "generate_stubs.py"), "--check",
                           str(BUILD_DIR)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr


def test_the_package_and_its_stubs_pass_mypy_strict(tmp_path):
    import hapticd

    package = pathlib.Path(hapticd.__file__).parent
    assert (package / "py.typed").exists() and (package / "_native.pyi").exists()
    done = mypy(tmp_path, "-p", "hapticd")
    assert done.returncode == 0, done.stdout + done.stderr


def test_a_typed_program_passes_mypy_strict_and_runs(tmp_path, server):
    done = mypy(tmp_path, str(pathlib.Path(typed_example.__file__)))
    assert done.returncode == 0, done.stdout + done.stderr

    stiffness, force, events = typed_example.press_on_a_sphere(server.address)
    assert stiffness > 1000.0
    assert force[2] == pytest.approx(2.0, rel=0.05)
    assert all(isinstance(kind, str) for kind in events)  # when the watch starts is its own


def test_mistakes_are_caught_by_the_stubs(tmp_path):
    program = tmp_path / "mistakes.py"
    program.write_text(
        "import hapticd\n"
        "hapticd.SphereSpec(radius='big')\n"
        "hapticd.SphereSpec(raduis=0.5)\n"
        "def f(client: hapticd.Client) -> int:\n"
        "    return client.poll_state(timeout=0.1).tick\n"
        "def g(client: hapticd.Client) -> str:\n"
        "    return client.add_wall(hapticd.WallSpec()).id\n")
    done = mypy(tmp_path, str(program))
    assert done.returncode == 1, done.stdout + done.stderr
    for expected in ['mistakes.py:2: error: Argument "radius" to "SphereSpec" has incompatible '
                     'type "str"; expected "float"',
                     'mistakes.py:3: error: Unexpected keyword argument "raduis" for "SphereSpec"',
                     'mistakes.py:5: error: Item "None" of "Optional[State]" has no attribute "tick"',
                     'mistakes.py:7: error: Incompatible return value type (got "int", expected '
                     '"str")']:
        assert expected in done.stdout, done.stdout
