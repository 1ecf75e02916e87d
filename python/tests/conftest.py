"""Fixtures for the Python SDK's tests: a real hapticd in lockstep time on ephemeral loopback
ports (readiness from --ready-file, never a sleep), and clients of it."""

import json
import os
import pathlib
import signal
import subprocess
import tempfile
import time

import pytest

import hapticd

HAPTICD_BINARY = os.environ.get("HAPTICD_BINARY", "hapticd")


def lockstep_config(**extra):
    """A lockstep ServerConfig (as JSON text) for tests; keyword arguments are spliced in."""
    config = {
        "time_mode": "LOCKSTEP",
        "udp_address": "127.0.0.1",
        "status_period_s": 0,
        "real_time": {"use_fifo": False},
        "simulated_point_mass": {"initial_position": {"z": 0.02}},
    }
    config.update(extra)
    return json.dumps(config)


class ServerProcess:
    """The hapticd binary run with `config_json` (a haptic.v1.ServerConfig); stop() sends SIGTERM
    and returns the exit status."""

    def __init__(self, config_json, extra_args=()):
        self.dir = pathlib.Path(tempfile.mkdtemp(prefix="hapticd-pytest-"))
        config_path = self.dir / "config.json"
        ready_path = self.dir / "ready.json"
        config_path.write_text(config_json)
        self.log = open(self.dir / "server.log", "w")
        self.process = subprocess.Popen(
            [HAPTICD_BINARY, "--config", str(config_path), "--grpc-address", "127.0.0.1:0",
             "--udp-port", "0", "--ready-file", str(ready_path), *extra_args],
            stdout=self.log, stderr=subprocess.STDOUT)
        give_up = time.monotonic() + 20.0
        while not ready_path.exists():
            if self.process.poll() is not None:
                raise RuntimeError(f"hapticd exited ({self.process.returncode}) before it was "
                                   f"ready: {(self.dir / 'server.log').read_text()}")
            if time.monotonic() > give_up:
                self.stop()
                raise RuntimeError("hapticd not ready within 20 s")
            time.sleep(0.005)
        ready = json.loads(ready_path.read_text())
        self.address = f"127.0.0.1:{ready['grpc_port']}"

    def stop(self):
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.log.close()
        return self.process.returncode

    def config(self, **overrides):
        """A ClientConfig for this server, heartbeating every 20 ms (well inside any lease)."""
        settings = {"server_address": self.address, "client_name": "pytest",
                    "heartbeat_period": 0.02}
        settings.update(overrides)
        return hapticd.ClientConfig(**settings)


@pytest.fixture
def server():
    """A lockstep hapticd with the default simulated point mass, the tool at z = 20 mm."""
    process = ServerProcess(lockstep_config())
    yield process
    assert process.stop() == 0


@pytest.fixture
def client(server):
    with hapticd.Client(server.config()) as connected:
        yield connected
