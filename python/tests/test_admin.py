"""Statistics, recordings and tokens through the Python SDK."""

import json

import pytest

import hapticd
from conftest import ServerProcess, lockstep_config

ADMIN = "admin-token-0123456789abcdef"
OBSERVER = "observer-token-0123456789abcdef"


def test_stats_count_this_session_and_its_stream(client):
    wall = client.add_wall(hapticd.WallSpec(normal=(0, 0, 1),
                                            impedance=hapticd.Impedance(stiffness=500)))
    client.step(100)
    stats = client.stats()
    assert stats.ticks >= 100 and stats.objects == 1 and stats.sessions == 1
    assert [c.client_name for c in stats.clients] == ["pytest"]
    assert stats.clients[0].decimation == 1
    assert client.receive_counters().rejected == 0
    del wall  # a handle no one holds removes its object
    client.step(100)
    assert client.stats().objects == 0


def test_a_recording_counts_the_samples_it_wrote(tmp_path):
    server = ServerProcess(lockstep_config(recording_dir=str(tmp_path)))
    try:
        with hapticd.Client(server.config()) as client:
            started = client.start_recording("run.hrec")
            client.step(250)
            stopped = client.stop_recording()
            assert stopped.samples == 250
            assert stopped.path == started.path
            with pytest.raises(hapticd.FailedPreconditionError):
                client.stop_recording()
    finally:
        assert server.stop() == 0


def test_tokens_and_roles_apply_to_python_clients():
    security = {"tokens": [{"name": "root", "token": ADMIN, "role": "ADMIN"},
                           {"name": "viewer", "token": OBSERVER, "role": "OBSERVER"}]}
    server = ServerProcess(lockstep_config(security=security))
    try:
        with pytest.raises(hapticd.UnauthenticatedError):
            hapticd.Client(server.config())
        with hapticd.Client(server.config(token=OBSERVER)) as observer:
            with pytest.raises(hapticd.PermissionDeniedError, match="OBSERVER") as refused:
                observer.step(1)
            assert refused.value.code == hapticd.ErrorCode.PERMISSION_DENIED
            with hapticd.Client(server.config(token=ADMIN, client_name="root")) as admin:
                admin.step(1)
                sessions = {s.token_name: s.role for s in admin.sessions()}
                assert sessions == {"viewer": hapticd.Role.OBSERVER, "root": hapticd.Role.ADMIN}
    finally:
        assert server.stop() == 0
