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


CERTS = pathlib.Path(os.environ.get("HAPTIC_TEST_CERTS", ""))
TOKEN = "python-example-token-0123456789"


def test_the_example_reaches_a_server_with_mutual_tls_and_a_token(tmp_path):
    security = {"tls": {"cert_file": str(CERTS / "server.pem"), "key_file": str(CERTS / "server.key"),
                        "client_ca_file": str(CERTS / "ca.pem")},
                "tokens": [{"name": "rig", "token": TOKEN, "role": "CONTROLLER"}]}
    server = ServerProcess(lockstep_config(security=security))
    token_file = tmp_path / "token"
    token_file.write_text(TOKEN + "\n")
    token_file.chmod(0o600)
    example = [sys.executable, str(EXAMPLE / "touch_wall.py"), server.address, "--lockstep"]
    try:
        secured = subprocess.run([*example, "--ca", str(CERTS / "ca.pem"), "--cert", str(CERTS / "client.pem"),
                                  "--key", str(CERTS / "client.key"), "--token-file", str(token_file)],
                                 capture_output=True, text=True, timeout=120)
        plaintext = subprocess.run(example, capture_output=True, text=True, timeout=60)
        no_token = subprocess.run([*example, "--ca", str(CERTS / "ca.pem"), "--cert", str(CERTS / "client.pem"),
                                   "--key", str(CERTS / "client.key")], capture_output=True, text=True, timeout=60)
        half = subprocess.run([*example, "--cert", str(CERTS / "client.pem")], capture_output=True, text=True,
                              timeout=60)
    finally:
        server.stop()
    assert secured.returncode == 0, secured.stderr
    rows = [line for line in secured.stdout.splitlines() if line.strip()[:1].isdigit()]
    assert len(rows) == 60 and rows[-1].split()[4] == "yes"
    assert plaintext.returncode == 1
    assert "the server speaks TLS" in plaintext.stderr and "(--ca)" in plaintext.stderr
    assert no_token.returncode == 1 and "token" in no_token.stderr.lower(), no_token.stderr
    assert half.returncode == 2 and "--cert, --key and --server-name need --ca" in half.stderr


def test_the_example_names_the_interpreter_when_the_module_is_not_found(tmp_path):
    # A copy of the example where no build tree sits beside it, and no PYTHONPATH: as run by a
    # python3 that is not the one the module was built for.
    copy = tmp_path / "examples" / "python" / "touch_wall.py"
    copy.parent.mkdir(parents=True)
    copy.write_text((EXAMPLE / "touch_wall.py").read_text())
    environment = {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}
    done = subprocess.run([sys.executable, "-S", str(copy)], capture_output=True, text=True, timeout=60,
                          env=environment)
    assert done.returncode == 1
    assert f"cannot import hapticd" in done.stderr and sys.executable in done.stderr, done.stderr
