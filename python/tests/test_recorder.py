"""Client.record: every State the client accepts, in CSV and HDF5, read back with the csv module and
h5py and compared field by field with what the on_state callback saw; bad options refused naming
the field; the recorder as a context manager."""

import csv
import math
import threading
import time

import h5py
import numpy as np
import pytest

import hapticd


def wait_until(predicate, timeout=10.0):
    """Polls `predicate` until true or `timeout` s pass; its last value."""
    give_up = time.monotonic() + timeout
    while not predicate() and time.monotonic() < give_up:
        time.sleep(0.002)
    return predicate()


VECTORS = {"position": "m", "velocity": "m_s", "force": "N", "proxy": "m"}


def expected_row(state):
    """A State as the files hold it: column name -> value (NaN for absent orientation/torque)."""
    row = {"tick": state.tick, "sequence": state.sequence, "server_time_s": state.server_time,
           "contact_count": state.contact_count, "flags": state.flags, "buttons": state.buttons}
    for name, unit in VECTORS.items():
        for axis, value in zip("xyz", getattr(state, name)):
            row[f"{name}_{axis}_{unit}"] = float(value)
    orientation = state.orientation if state.orientation is not None else [math.nan] * 4
    for axis, value in zip("wxyz", orientation):
        row[f"orientation_{axis}"] = float(value)
    torque = state.torque if state.torque is not None else [math.nan] * 3
    for axis, value in zip("xyz", torque):
        row[f"torque_{axis}_Nm"] = float(value)
    return row


def same(a, b):
    return (math.isnan(a) and math.isnan(b)) or a == b


def check_rows(rows_by_tick, seen, what):
    assert seen, "the callback saw nothing"
    for tick, (state, received_at) in seen.items():
        assert tick in rows_by_tick, f"{what}: no row for tick {tick}"
        row = rows_by_tick[tick]
        for name, value in expected_row(state).items():
            assert same(float(row[name]), float(value)), f"{what} tick {tick} {name}: {row[name]} vs {value}"
        # received_ns on the monotonic clock the State's received_at (s) is read on.
        assert int(row["received_ns"]) / 1e9 == received_at, f"{what} tick {tick} received_ns"


def test_record_writes_every_accepted_sample_to_csv_and_hdf5_as_the_callback_saw_it(client, tmp_path):
    seen = {}
    lock = threading.Lock()

    def on_state(state):
        with lock:
            seen[state.tick] = (state, state.received_at)

    client.on_state(on_state)
    accepted_before = client.receive_counters().accepted
    with client.record(tmp_path / "session.csv") as csv_recorder, \
            client.record(str(tmp_path / "session.h5")) as h5_recorder:
        assert csv_recorder.recording
        assert csv_recorder.events_path == str(tmp_path / "session.events.csv")
        wall = client.add_wall(hapticd.WallSpec(normal=(0, 0, 1),
                                                impedance=hapticd.Impedance(stiffness=1000, damping=1)))
        client.set_operator(hapticd.OperatorInput.push((0, 0, -5)))
        for chunk in range(10):
            if chunk == 6:
                wall.remove()
            last = client.step(25)
            assert wait_until(lambda: last in seen), f"the callback never saw tick {last}"
        assert wait_until(lambda: csv_recorder.stats().events_written >= 3
                          and h5_recorder.stats().events_written >= 3)
        accepted = client.receive_counters().accepted - accepted_before
    client.on_state(None)
    assert not csv_recorder.recording
    csv_stats = csv_recorder.close()  # again, after the with block: the same totals
    h5_stats = h5_recorder.close()
    for stats in (csv_stats, h5_stats):
        assert stats.samples_received == accepted > 0
        assert stats.samples_written == accepted
        assert stats.dropped == 0 and stats.write_errors == 0 and stats.first_error == ""
        assert stats.events_written >= 3

    with open(tmp_path / "session.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == accepted
    ticks = [int(row["tick"]) for row in rows]
    assert ticks == sorted(ticks)
    check_rows({int(row["tick"]): row for row in rows}, seen, "CSV")
    with open(tmp_path / "session.events.csv", newline="") as f:
        events = list(csv.DictReader(f))
    assert events[0]["kind_name"] == "watch_started"
    assert int(events[0]["kind"]) == int(hapticd.Event.Kind.WATCH_STARTED)
    scene = [event["message"] for event in events if event["kind_name"] == "scene_changed"]
    assert len(scene) == 2 and "created" in scene[0] and "deleted" in scene[1]

    with h5py.File(tmp_path / "session.h5", "r") as f:
        samples = f["samples"]
        assert samples["position_x_m"].attrs["unit"] == "m"
        assert f.attrs["client_name"] == "pytest"
        assert f.attrs["device_name"] == client.device_info.name
        columns = {name: samples[name][()] for name in samples}
        assert all(len(values) == accepted for values in columns.values())
        assert columns["tick"].dtype == np.uint64
        by_tick = {int(tick): {name: values[i] for name, values in columns.items()}
                   for i, tick in enumerate(columns["tick"])}
        check_rows(by_tick, seen, "HDF5")
        kinds = f["events/kind"][()]
        names = [name.decode() for name in f["events/kind_name"][()]]
        assert kinds[0] == int(hapticd.Event.Kind.WATCH_STARTED) and names[0] == "watch_started"
        assert names.count("scene_changed") == 2


@pytest.mark.parametrize("options, says", [
    ({"path": ""}, "record: path: empty"),
    ({"path": "{dir}/session.txt"}, "ends in neither .csv nor .h5"),
    ({"path": "{dir}/session.csv", "queue_capacity": 0}, "record: queue_capacity: must be >= 1"),
    ({"path": "{dir}/session.csv", "format": "xml"}, "record: format: 'xml' is none of"),
    ({"path": "{dir}/missing/session.h5"}, "record: path: the directory"),
    ({"path": "{dir}/kept.h5"}, "exists (RecorderOptions::overwrite replaces it)"),
])
def test_record_refuses_bad_options_naming_the_field(client, tmp_path, options, says):
    (tmp_path / "kept.h5").write_text("mine")
    options = dict(options)
    path = options.pop("path").format(dir=tmp_path)
    with pytest.raises(hapticd.InvalidArgumentError, match=None) as raised:
        client.record(path, **options)
    assert says in str(raised.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.h5"]
    assert (tmp_path / "kept.h5").read_text() == "mine"


def test_record_overwrites_only_when_asked_and_writes_no_events_file_without_events(client, tmp_path):
    (tmp_path / "old.csv").write_text("mine")
    recorder = client.record(tmp_path / "old.csv", events=False, overwrite=True, queue_capacity=16)
    assert recorder.events_path == ""
    last = client.step(5)
    assert client.wait_for_tick(last) is not None
    stats = recorder.close()
    assert stats.events_written == 0
    with open(tmp_path / "old.csv", newline="") as f:
        header = next(csv.reader(f))
    assert header[:4] == ["received_ns", "arrived_ns", "tick", "sequence"]
    assert not (tmp_path / "old.events.csv").exists()
