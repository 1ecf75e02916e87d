"""Statistics, recordings and tokens through the Python SDK."""

import json
import time

import pytest

import hapticd
from conftest import ServerProcess, lockstep_config
from dds_domain import unique_dds_domain

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
    assert stats.federation is None  # no federation section
    assert client.receive_counters().rejected == 0
    del wall  # a handle no one holds removes its object
    client.step(100)
    assert client.stats().objects == 0


def federation_section(site, domain):
    """A federation section on loopback DDS, in `domain` (one of the test's own: dds_domain.py)."""
    return {"site": site, "domain_id": domain,
            "peers": ["127.0.0.1"]}


def test_a_site_alone_has_federation_stats_and_no_coupling():
    server = ServerProcess(lockstep_config(federation=federation_section("py-alone", unique_dds_domain())))
    try:
        with hapticd.Client(server.config()) as client:
            client.step(10)
            federation = client.stats().federation
            assert isinstance(federation, hapticd.FederationStats)
            assert federation.couplings == []
            assert federation.items_refused == 0 and federation.wrenches_refused == 0
            assert federation.samples_failed == 0
    finally:
        assert server.stop() == 0


def test_two_sites_see_their_tools_coupling_and_its_books_balance():
    """Two real-time sites on loopback DDS, A's hand pushing its tool into B's: A holds B's tool
    as a coupling of its port 0, its user put energy into it, and its layer holds what its books
    say (injected − given + received − sent, to 1 mJ: the figures are read a tick apart)."""
    domain = unique_dds_domain()

    def site(name, x):
        return ServerProcess(json.dumps({
            "udp_address": "127.0.0.1", "status_period_s": 0, "real_time": {"use_fifo": False},
            "simulated_point_mass": {"initial_position": {"x": x}},
            "federation": federation_section(name, domain)}))

    a = site("py-a", -0.02)
    try:
        b = site("py-b", 0.02)
        try:
            with hapticd.Client(a.config()) as client:
                # The hand moves once A holds B's tool (discovery over DDS takes its time on a
                # loaded machine; a hand that had already passed B would push nothing into it).
                give_up = time.monotonic() + 10.0
                while not client.stats().federation.couplings and time.monotonic() < give_up:
                    time.sleep(0.05)
                hand = hapticd.OperatorInput.follow_line((-0.02, 0, 0), (0.03, 0, 0), 1.0,
                                                         hapticd.OperatorInput.Grip.CUSTOM)
                hand.stiffness = 200.0
                hand.damping = 2.0
                client.set_operator(hand)
                give_up = time.monotonic() + 10.0
                couplings = []
                while time.monotonic() < give_up:
                    couplings = client.stats().federation.couplings
                    if couplings and couplings[0].injected_j > 0.0:
                        break
                    time.sleep(0.05)  # polling the server's figures, not waiting for them
            assert len(couplings) == 1, "A never heard B's tool"
            coupling = couplings[0]
            assert coupling.kind == hapticd.CouplingStats.Kind.TOOL
            assert coupling.port == 0 and coupling.remote != 0 and coupling.mass == 0
            assert coupling.injected_j > 0.0, "A's hand put nothing into the coupling"
            assert coupling.reservoir_j == pytest.approx(
                coupling.injected_j - coupling.given_j + coupling.received_j - coupling.sent_j,
                abs=1e-3)
        finally:
            assert b.stop() == 0
    finally:
        assert a.stop() == 0


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
