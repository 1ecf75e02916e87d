"""Callbacks on the SDK's threads with the GIL handled: state, events, connection changes; a
callback that raises; stopping or dropping a client while its callback runs; Python threads."""

import gc
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import hapticd
from conftest import ServerProcess, lockstep_config


def wait_until(predicate, timeout=5.0):
    """Polls `predicate` until true or `timeout` s pass; its last value."""
    give_up = time.monotonic() + timeout
    while not predicate() and time.monotonic() < give_up:
        time.sleep(0.002)
    return predicate()


def test_on_state_runs_python_on_the_receive_thread_while_step_waits(client):
    seen = []
    threads = set()
    lock = threading.Lock()

    def on_state(state):
        with lock:
            seen.append((state.tick, state.position.copy()))
            threads.add(threading.get_ident())

    client.on_state(on_state)
    last = client.step(200)
    assert wait_until(lambda: len(seen) > 0 and seen[-1][0] == last)
    client.on_state(None)
    ticks = [tick for tick, _ in seen]
    assert ticks == sorted(ticks)
    assert threading.get_ident() not in threads  # not the caller's thread
    assert seen[-1][1].shape == (3,)
    with lock:
        count = len(seen)
    client.step(50)
    time.sleep(0.05)
    assert len(seen) == count  # stopped


def test_a_callback_that_raises_is_reported_and_the_stream_goes_on(client, monkeypatch):
    reported = []
    monkeypatch.setattr("sys.unraisablehook", lambda info: reported.append(info))
    calls = []

    def faulty(state):
        calls.append(state.tick)
        raise ValueError("a bug in the application's callback")

    client.on_state(faulty)
    last = client.step(20)
    assert wait_until(lambda: calls and calls[-1] == last)
    client.on_state(None)
    assert reported, "the exception went nowhere"
    assert isinstance(reported[0].exc_value, ValueError)
    assert "on_state" in str(reported[0].err_msg) or "on_state" in repr(reported[0].object)
    assert client.step(1) == last + 1  # the client still works


def test_stopping_a_slow_callback_or_dropping_its_client_does_not_deadlock(server):
    client = hapticd.Client(server.config())
    inside = threading.Event()

    def slow(state):
        inside.set()
        time.sleep(0.2)  # holds the GIL at times, and the receive thread throughout

    client.on_state(slow)
    client.step(5)
    assert inside.wait(5)
    started = time.monotonic()
    client.on_state(None)  # waits for the callback, which needs the GIL this thread let go
    assert time.monotonic() - started < 5
    inside.clear()
    client.on_state(slow)
    client.step(5)
    assert inside.wait(5)
    del client  # the destructor joins the receive thread: it too lets go of the GIL
    gc.collect()


def test_events_arrive_in_order_with_their_items(client):
    events = []
    client.on_event(events.append)
    assert wait_until(lambda: any(e.kind == hapticd.Event.Kind.WATCH_STARTED for e in events))
    wall = client.add_wall(hapticd.WallSpec(normal=(0, 0, 1),
                                            impedance=hapticd.Impedance(stiffness=500)))
    wall_id = wall.id
    wall.remove()
    client.step(1)

    def changes():
        return [(e.item_id, e.message) for e in events if e.kind == hapticd.Event.Kind.SCENE_CHANGED]

    assert wait_until(lambda: len(changes()) >= 2)
    client.on_event(None)
    assert changes()[:2] == [(wall_id, f"object {wall_id} created"),
                             (wall_id, f"object {wall_id} deleted")]
    with pytest.raises(TypeError, match="expected a callable or None"):
        client.on_event(42)


def test_a_kicked_client_hears_that_its_session_ended(server):
    with hapticd.Client(server.config(client_name="admin")) as admin, \
         hapticd.Client(server.config(client_name="visitor")) as visitor:
        changes = []
        visitor.on_connection(changes.append)
        names = {s.client_name: s for s in admin.sessions()}
        assert set(names) == {"admin", "visitor"}
        admin.kick_session(visitor.session_id, "the demo is over")
        assert wait_until(lambda: len(changes) >= 1)
        assert changes[0].state == hapticd.ConnectionChange.State.ENDED
        assert "the demo is over" in changes[0].reason
        assert visitor.connection_state == hapticd.ConnectionChange.State.ENDED
        with pytest.raises(hapticd.PermissionDeniedError, match="ended by an admin: the demo is over"):
            visitor.step(1)


def test_python_threads_share_one_client(client):
    errors = []
    steps = 50

    def stepper():
        try:
            for _ in range(steps):
                client.step(1)
        except Exception as error:  # noqa: BLE001 (reported below)
            errors.append(error)

    def reader():
        try:
            for _ in range(steps):
                client.scene()
                client.poll_state(timeout=0.01)
        except Exception as error:  # noqa: BLE001
            errors.append(error)

    workers = [threading.Thread(target=stepper) for _ in range(2)] + \
              [threading.Thread(target=reader) for _ in range(2)]
    first = client.step(1)
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(30)
    assert not errors
    assert client.step(1) == first + 2 * steps + 1


def test_samples_carry_monotonic_times_and_interpolate_between_frames(client):
    client.set_operator(hapticd.OperatorInput.push((0, 0, -0.5)))
    before = time.monotonic()
    a = client.wait_for_tick(client.step(5))
    b = client.wait_for_tick(client.step(5))
    after = time.monotonic()
    assert before <= a.received_at <= b.received_at <= after
    middle = hapticd.interpolate_position(a, b, (a.server_time + b.server_time) / 2)
    assert middle.shape == (3,)
    assert min(a.position[2], b.position[2]) <= middle[2] <= max(a.position[2], b.position[2])
    np.testing.assert_allclose(hapticd.interpolate_position(a, b, b.server_time), b.position)
    ahead = hapticd.predict_position(a, b, b.server_time + 0.005)
    assert ahead[2] < b.position[2]  # still falling


def test_a_program_that_exits_with_callbacks_running_exits_cleanly():
    # The interpreter closes every open Client at exit (atexit) before it finalizes: a callback
    # entering Python after that would be cut off on the SDK's thread and crash the process.
    # A real-time server keeps the callbacks coming while the program ends.
    server = ServerProcess(lockstep_config(time_mode="REAL_TIME"))
    script = f"""
import threading, time, hapticd
client = hapticd.Client(server_address={server.address!r})
calls = []
def slow(state):
    calls.append(state.tick)
    time.sleep(0.001)  # lets go of the GIL, and takes it back
client.on_state(slow)
while len(calls) < 50:
    time.sleep(0.01)
print("leaving with the callbacks running", flush=True)
"""
    try:
        for _ in range(3):
            done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                                  timeout=60)
            assert done.returncode == 0, (done.returncode, done.stderr)
            assert "leaving with the callbacks running" in done.stdout
    finally:
        assert server.stop() == 0
