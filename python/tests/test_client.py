"""Sessions with a lockstep hapticd: every object and field kind, handles as context managers,
state as NumPy arrays, stepping, scenes, errors."""

import numpy as np
import pytest

import hapticd
from conftest import ServerProcess, lockstep_config

STIFF = hapticd.Impedance(stiffness=1000.0, damping=1.0)


def every_object_kind():
    pose = hapticd.Pose(position=(0.3, 0.3, 0.3))
    return [
        hapticd.WallSpec(point=(0, 0, -0.05), normal=(0, 0, 1), impedance=STIFF),
        hapticd.SphereSpec(center=(0.2, 0, 0), radius=0.01, impedance=STIFF),
        hapticd.BoxSpec(pose=pose, half_extents=(0.01, 0.02, 0.03), impedance=STIFF),
        hapticd.CapsuleSpec(pose=pose, radius=0.01, half_length=0.02, impedance=STIFF),
        hapticd.TangentPlaneSpec(pose=pose, normal=(0, 1, 0), tangential_stiffness=50.0,
                                 impedance=STIFF),
        hapticd.MeshSpec(pose=pose, vertices=[[0, 0, 0], [0.05, 0, 0], [0, 0.05, 0], [0, 0, 0.05]],
                         indices=[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], impedance=STIFF),
    ]


def every_field_kind():
    return [
        hapticd.SpringFieldSpec(anchor=(0, 0, 0.02), stiffness=20.0, max_force=2.0),
        hapticd.DistanceSpringSpec(anchor=hapticd.Distance(kind=hapticd.Distance.Kind.LINE,
                                                           axis=(1, 0, 0)), stiffness=10.0),
        hapticd.PotentialFieldSpec(distance=hapticd.Distance(origin=(0.5, 0, 0)), gain=10.0,
                                   offset=0.01),
        hapticd.LinearFieldSpec(origin=(0.5, 0.5, 0), force=(0, 0, 0.1), radius=0.01,
                                fade_width=0.005),
        hapticd.ViscousFieldSpec(damping=0.5, center=(0.5, 0.5, 0.5), radius=0.01,
                                 fade_width=0.005),
        hapticd.DetentFieldSpec(distance=hapticd.Distance(origin=(-0.5, 0, 0)), depth=0.01,
                                radius=0.01, rim_height=0.001, rim_width=0.005),
        # Registered on the point mass too (they act on a device that measures the orientation).
        hapticd.OrientationSpringSpec(target=(0.5, 0.5, -0.5, 0.5), stiffness=0.5, damping=0.01,
                                      max_torque=0.1, law=hapticd.ImpedanceLaw.BACKWARD_DIFFERENCE),
        hapticd.OrientationDetentSpec(target=(0, 0, 0, 1), depth=0.01, radius=0.2,
                                      rim_height=0.002, rim_width=0.1, damping=0.001),
    ]


def test_a_session_reports_its_device_and_steps_with_numpy_state(client):
    info = client.device_info
    assert info.simulated and info.loop_rate_hz > 0
    assert info.workspace_min.shape == (3,)
    assert client.session_id > 0 and client.lease_timeout > 0
    tick = client.step(10)
    state = client.wait_for_tick(tick)
    assert state is not None and state.tick == tick
    assert isinstance(state.position, np.ndarray) and state.position.shape == (3,)
    assert state.position[2] == pytest.approx(0.02, abs=1e-3)
    assert client.wait_for_tick(tick + 1000, timeout=0.05) is None


def test_a_wall_pushes_back_and_goes_with_its_with_block(client):
    client.set_operator(hapticd.OperatorInput.push((0, 0, -2.0)))
    with client.add_wall(hapticd.WallSpec(normal=(0, 0, 1), impedance=STIFF)) as wall:
        assert wall.owned and wall.id > 0
        assert wall.stability.device_known
        trajectory = hapticd.record(client, 1000, every=10)
        assert trajectory.position.shape == (100, 3)
        # The hand's 2 N is held by the wall: about 2 mm deep, the force back up to 2 N.
        assert trajectory.position[-1, 2] == pytest.approx(-2.0 / 1000.0, rel=0.05)
        assert trajectory.force[-1, 2] == pytest.approx(2.0, rel=0.05)
        assert trajectory.contact_count[-1] == 1
        assert np.all(np.diff(trajectory.tick.astype(np.int64)) == 10)
        assert [o for o in client.scene().object_ids] == [wall.id]
    assert not wall.owned
    assert client.scene().object_ids == []


def test_every_object_and_field_kind_registers_reads_back_and_updates(client):
    objects = [client.add(spec) for spec in every_object_kind()]
    fields = [client.add(spec) for spec in every_field_kind()]
    registered = client.scene()
    assert registered.object_ids == [o.id for o in objects]
    assert registered.field_ids == [f.id for f in fields]
    for given, held in zip(every_object_kind(), registered.scene.objects):
        assert type(held) is type(given)
    for given, held in zip(every_field_kind(), registered.scene.fields):
        assert type(held) is type(given)
    assert registered.scene.fields[6:] == every_field_kind()[6:]  # as given, whole
    sphere = registered.scene.objects[1]
    assert sphere.radius == 0.01 and np.allclose(sphere.center, [0.2, 0, 0])

    objects[1].update(hapticd.SphereSpec(center=(0.2, 0, 0), radius=0.03, impedance=STIFF))
    fields[4].update(hapticd.ViscousFieldSpec(damping=1.5))
    fields[7].update(hapticd.OrientationSpringSpec(stiffness=0.2))  # a detent becomes a spring
    registered = client.scene()
    assert registered.scene.objects[1].radius == 0.03
    assert registered.scene.fields[4].damping == 1.5
    assert registered.scene.fields[7] == hapticd.OrientationSpringSpec(stiffness=0.2)
    for handle in objects + fields:
        handle.remove()
    assert client.scene().object_ids == [] and client.scene().field_ids == []


def test_a_refused_spec_names_the_field_and_changes_nothing(client):
    with client.add_sphere(hapticd.SphereSpec(center=(0, 0, 0.1), radius=0.01,
                                              impedance=STIFF)) as sphere:
        with pytest.raises(hapticd.InvalidArgumentError, match=r"object.sphere.radius") as refused:
            sphere.update(hapticd.SphereSpec(radius=-1.0, impedance=STIFF))
        assert refused.value.code == hapticd.ErrorCode.INVALID_ARGUMENT
        assert client.scene().scene.objects[0].radius == 0.01
        with pytest.raises(hapticd.InvalidArgumentError, match=r"triangle|indices|vertices"):
            client.add_mesh(hapticd.MeshSpec(vertices=[[0, 0, 0]], indices=[0, 0, 5],
                                             impedance=STIFF))
        assert client.scene().object_ids == [sphere.id]


def test_an_item_across_sites_is_refused_outside_a_federation_and_nothing_is_created(client):
    not_federated = (r"across_sites: this server is not in a federation \(its configuration has "
                     r"no federation section\)")
    with pytest.raises(hapticd.FailedPreconditionError,
                       match=r"^CreateObject: object\." + not_federated) as refused:
        client.add_sphere(hapticd.SphereSpec(center=(0, 0, 0.1), radius=0.01, impedance=STIFF,
                                             across_sites=True))
    assert refused.value.code == hapticd.ErrorCode.FAILED_PRECONDITION
    with pytest.raises(hapticd.FailedPreconditionError, match=r"^CreateField: field\." + not_federated):
        client.add(hapticd.ViscousFieldSpec(damping=0.5, across_sites=True))
    with pytest.raises(hapticd.FailedPreconditionError,
                       match=r"^ApplyScene: scene\.fields\[0\]\." + not_federated):
        client.apply_scene(hapticd.SceneSpec(objects=every_object_kind()[:1],
                                             fields=[hapticd.ViscousFieldSpec(across_sites=True)]))
    registered = client.scene(all_sessions=True)
    assert registered.object_ids == [] and registered.field_ids == []


def test_a_scene_applies_whole_from_specs_and_from_a_file(client, tmp_path):
    scene = hapticd.SceneSpec(objects=every_object_kind(), fields=every_field_kind())
    with client.apply_scene(scene) as applied:
        assert len(applied.objects) == 6 and len(applied.fields) == 8
        assert len(client.last_scene_stability) == 6
        held = client.scene().scene
        assert held.objects == scene.objects and held.fields == scene.fields
    assert client.scene().object_ids == []

    bad = hapticd.SceneSpec(objects=[hapticd.WallSpec(normal=(0, 0, 1), impedance=STIFF),
                                     hapticd.BoxSpec(half_extents=(0.01, -1, 0.01))])
    with pytest.raises(hapticd.InvalidArgumentError, match=r"scene.objects\[1\]"):
        client.apply_scene(bad)

    path = tmp_path / "scene.json"
    path.write_text(hapticd.scene_json(scene))
    applied = client.apply_scene_file(str(path))
    assert [h.id for h in applied.objects] == client.scene().object_ids
    with pytest.raises(hapticd.InvalidArgumentError, match="missing.json"):
        client.apply_scene_file(str(tmp_path / "missing.json"))


def test_a_pushed_virtual_mass_moves_and_energy_is_accounted(client):
    sphere = client.add_sphere(hapticd.SphereSpec(
        center=(0, 0, 0.0), radius=0.015, impedance=STIFF,
        dynamics=hapticd.Dynamics(mass=0.1, damping=1.0)))
    client.set_operator(hapticd.OperatorInput.push((0, 0, -1.0)))
    client.step(1000)
    moved = {s.id: s for s in client.object_states()}[sphere.id]
    assert moved.position[2] < -0.001  # pushed down
    energy = {e.id: e for e in client.scene_energy()}[sphere.id]
    assert energy.is_object and energy.absorbed_from_device > 0


def test_reset_reproduces_a_run_bit_for_bit(client):
    def run():
        client.add_wall(hapticd.WallSpec(normal=(0, 0, 1), impedance=STIFF)).release()
        client.set_operator(hapticd.OperatorInput.follow((0, 0, -0.01), 200.0, 2.0))
        return hapticd.record(client, 300)

    first = run()
    client.reset()
    second = run()
    np.testing.assert_array_equal(first.tick, second.tick)
    np.testing.assert_array_equal(first.position, second.position)
    np.testing.assert_array_equal(first.force, second.force)


def test_record_refuses_counts_that_are_not_positive_whole_numbers(client):
    with pytest.raises(ValueError, match="ticks must be a whole number >= 1"):
        hapticd.record(client, 0)
    with pytest.raises(ValueError, match="every must be a whole number >= 1"):
        hapticd.record(client, 10, every=2.5)


def test_a_closed_client_refuses_calls_and_closing_twice_is_harmless(server):
    client = hapticd.Client(server.config())
    client.close()
    client.close()
    with pytest.raises(hapticd.Error):
        client.step(1)


def test_leaving_a_with_block_does_not_raise_when_the_server_is_gone():
    server = ServerProcess(lockstep_config())
    try:
        with hapticd.Client(server.config(rpc_timeout=2.0)) as client:
            client.step(1)
            server.process.kill()  # no goodbye: the session's CloseSession cannot reach it
            server.process.wait()
        # The block's own exception comes out as it is, not a CloseSession ConnectionError.
        server = ServerProcess(lockstep_config())
        with pytest.raises(KeyError, match="the block's own"):
            with hapticd.Client(server.config(rpc_timeout=2.0)) as client:
                server.process.kill()
                server.process.wait()
                raise KeyError("the block's own")
    finally:
        server.stop()


def test_no_server_is_a_connection_error():
    with pytest.raises(hapticd.ConnectionError, match="OpenSession") as refused:
        hapticd.Client(server_address="127.0.0.1:1", rpc_timeout=0.3)
    assert refused.value.code == hapticd.ErrorCode.CONNECTION


def test_a_bad_option_is_named():
    with pytest.raises(TypeError, match="Client\\(\\) has no option 'adress'"):
        hapticd.Client(adress="127.0.0.1:1")


def test_a_6dof_device_streams_the_torque_of_an_orientation_spring():
    server = ServerProcess(lockstep_config(simulated_point_mass={
        "initial_position": {"z": 0.02}, "rotation": {}}))  # the handle at identity
    try:
        with hapticd.Client(server.config(client_name="stepper", state_decimation=0)) as stepper, \
             hapticd.Client(server.config(client_name="watcher")) as watcher:
            assert stepper.device_info.capabilities.orientation
            # The target 0.2 rad about +z: the spring turns the handle that way, |τ| <= K θ.
            half = 0.1
            spring = stepper.add_field(hapticd.OrientationSpringSpec(
                target=(np.cos(half), 0, 0, np.sin(half)), stiffness=0.05))
            last = stepper.step(20)
            replied = stepper.wait_for_tick(last)  # from the Step reply
            streamed = watcher.wait_for_tick(last)  # from the StateOriented datagram
            for state in (replied, streamed):
                assert state.orientation is not None and state.torque is not None
                assert state.torque[2] > 0 and state.torque[2] <= 0.05 * 0.2
                assert state.torque[0] == 0 and state.torque[1] == 0
            np.testing.assert_array_equal(replied.torque, streamed.torque)
            np.testing.assert_array_equal(replied.orientation, streamed.orientation)
            spring.remove()
    finally:
        assert server.stop() == 0


def test_two_users_on_two_device_ports_share_one_scene():
    server = ServerProcess(lockstep_config(extra_devices=[
        {"simulated_point_mass": {"initial_position": {"y": 0.05, "z": 0.02}}}]))
    try:
        with hapticd.Client(server.config(client_name="left")) as left, \
             hapticd.Client(server.config(client_name="right", device_index=1)) as right:
            assert right.device_info.simulated
            box = left.add_box(hapticd.BoxSpec(pose=hapticd.Pose(position=(0, 0.025, 0)),
                                               half_extents=(0.1, 0.1, 0.01), impedance=STIFF))
            right.set_operator(hapticd.OperatorInput.push((0, 0, -1.0)))
            last = left.step(1000)
            mine, theirs = left.wait_for_tick(last), right.wait_for_tick(last)
            assert mine.position[1] == pytest.approx(0.0) and theirs.position[1] == pytest.approx(0.05)
            assert mine.contact_count == 0 and mine.position[2] == pytest.approx(0.02, abs=1e-4)
            # The right user's tool rests on the left user's box: 1 N over 1000 N/m, 1 mm deep.
            assert theirs.contact_count == 1
            assert theirs.position[2] == pytest.approx(0.01 - 0.001, rel=0.02)
            assert right.scene(all_sessions=True).object_sessions == [left.session_id]
            assert right.scene().object_ids == []  # none of its own
            box.remove()
    finally:
        assert server.stop() == 0
