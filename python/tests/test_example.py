"""examples/python/touch_wall.py against a lockstep server: it prints the same rows as its C++
twin (examples/touch_wall) on a server of its own, ends in equilibrium with the hand, and names an
unreachable server."""

import os
import pathlib
import subprocess
import sys

import pytest

from conftest import ServerProcess, lockstep_config

EXAMPLE = pathlib.Path(os.environ.get("HAPTIC_EXAMPLES_DIR",
                                      pathlib.Path(__file__).parents[2] / "examples" / "python"))
CPP_TWIN = os.environ.get("TOUCH_WALL_BINARY")


def run(command):
    server = ServerProcess(lockstep_config())
    try:
        done = subprocess.run([*command, server.address, "--lockstep"], capture_output=True,
                              text=True, timeout=120)
    finally:
        server.stop()
    assert done.returncode == 0, done.stderr
    return [line.split() for line in done.stdout.splitlines() if line.strip()[:1].isdigit()]


def test_the_example_ends_pressed_into_the_wall_in_equilibrium_with_the_hand():
    table = run([sys.executable, str(EXAMPLE / "touch_wall.py")])
    assert len(table) == 60  # 3 s, a row per 50 ms
    assert table[0][4] == "no" and table[-1][4] == "yes"
    z = float(table[-1][2]) * 1e-3
    force = float(table[-1][3])
    assert z < 0
    # At rest the wall and the spring field together hold the hand's pull, 200 N/m towards 10 mm
    # below the surface (the example's HAND_STIFFNESS and END_Z).
    assert force == pytest.approx(200.0 * (z + 0.01), abs=0.002)


@pytest.mark.skipif(not CPP_TWIN, reason="TOUCH_WALL_BINARY not set (examples not built)")
def test_the_example_prints_what_its_cpp_twin_prints():
    assert run([sys.executable, str(EXAMPLE / "touch_wall.py")]) == run([CPP_TWIN])


def test_the_example_draws_its_chart(server, tmp_path):
    chart = tmp_path / "touch_wall.png"
    done = subprocess.run([sys.executable, str(EXAMPLE / "touch_wall.py"), server.address,
                           "--lockstep", "--plot", str(chart)], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert chart.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_an_unreachable_server_is_named():
    done = subprocess.run([sys.executable, str(EXAMPLE / "touch_wall.py"), "127.0.0.1:1"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode != 0
    assert "cannot connect to 127.0.0.1:1: nothing listens there" in done.stderr
    assert "Start one with ./scripts/run" in done.stderr
