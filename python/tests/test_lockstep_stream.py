"""Every tick of a lockstep step reaches a Python recorder: step(100000) recorded to CSV and HDF5
holds every tick once, in order, numbered without a gap, with nothing counted lost or dropped; and
a client that turns flow control off and reads slowly sees each loss as a gap and a count."""

import csv
import time

import h5py
import numpy as np

import hapticd


def wait_until_quiet(client, quiet=0.1, timeout=30.0):
    """Waits until the client has accepted no State for `quiet` s (what was sent has arrived)."""
    last = client.receive_counters().accepted
    give_up = time.monotonic() + timeout
    while time.monotonic() < give_up:
        time.sleep(quiet)
        now = client.receive_counters().accepted
        if now == last:
            return
        last = now


def csv_ticks_and_sequences(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return (np.array([int(r["tick"]) for r in rows], dtype=np.int64),
            np.array([int(r["sequence"]) for r in rows], dtype=np.int64))


def h5_ticks_and_sequences(path):
    with h5py.File(path, "r") as f:
        return np.asarray(f["/samples/tick"][:]), np.asarray(f["/samples/sequence"][:])


def test_a_step_of_a_hundred_thousand_ticks_is_recorded_in_full(server, tmp_path):
    client = hapticd.Client(server.config(client_name="recorder"))
    try:
        csv_recorder = client.record(tmp_path / "step.csv", events=False)
        h5_recorder = client.record(tmp_path / "step.h5", events=False)
        first = client.step(1) + 1
        # The step(1) State in before the count starts (a loaded machine may hold it past 50 ms).
        assert client.wait_for_tick(first - 1, timeout=10.0) is not None
        wait_until_quiet(client, 0.05)
        before = client.receive_counters().accepted
        ticks = 100_000
        last = client.step(ticks)
        assert last == first + ticks - 1
        assert client.wait_for_tick(last, timeout=30.0) is not None
        wait_until_quiet(client)
        csv_stats = csv_recorder.close()
        h5_stats = h5_recorder.close()
        counters = client.receive_counters()
        assert counters.accepted - before == ticks
        assert counters.lost == 0
        assert csv_stats.dropped == 0 and h5_stats.dropped == 0
        stats = client.stats()
        assert stats.samples_missed == 0 and stats.samples_skipped == 0 and stats.ack_stalls == 0
        assert stats.clients[0].ack_window > 0
        for what, (tick, sequence) in (("CSV", csv_ticks_and_sequences(tmp_path / "step.csv")),
                                       ("HDF5", h5_ticks_and_sequences(tmp_path / "step.h5"))):
            keep = tick >= first
            tick, sequence = tick[keep], sequence[keep]
            assert len(tick) == ticks, f"{what}: {len(tick)} rows of {ticks}"
            assert np.array_equal(tick, np.arange(first, last + 1)), f"{what}: ticks missing or out of order"
            assert np.array_equal(np.diff(sequence), np.ones(ticks - 1)), f"{what}: a gap in the sequence"
    finally:
        client.close()


def test_without_flow_control_a_slow_readers_losses_are_gaps_and_counted(server, tmp_path):
    client = hapticd.Client(server.config(client_name="slow", lockstep_flow_control=False))
    try:
        def slow(state):  # the callback holds the receive thread: the socket overflows
            time.sleep(0.05)

        client.on_state(slow)
        recorder = client.record(tmp_path / "lossy.csv", events=False)
        lost_before = client.receive_counters().lost
        last = client.step(20_000)
        wait_until_quiet(client)
        # One more tick, read at leisure: its sequence shows a loss at the burst's tail as a gap.
        assert client.step(1) == last + 1
        assert client.wait_for_tick(last + 1, timeout=5.0) is not None
        wait_until_quiet(client)
        client.on_state(None)
        stats = recorder.close()
        lost = client.receive_counters().lost - lost_before
        tick, sequence = csv_ticks_and_sequences(tmp_path / "lossy.csv")
        assert stats.dropped == 0
        assert tick[-1] == last + 1
        assert lost > 0, "the reader kept up: the test shows nothing"
        # The stream began at tick 1, numbered 1: every missing tick is a missing number, and counted.
        assert np.array_equal(np.diff(np.concatenate(([0], tick))), np.diff(np.concatenate(([0], sequence))))
        assert len(tick) + lost == last + 1
    finally:
        client.close()
