"""The value types: keyword construction, NumPy conversions, refusals that name the field."""

import copy

import numpy as np
import pytest

import hapticd


def test_specs_take_their_fields_by_keyword_and_compare_by_value():
    wall = hapticd.WallSpec(point=(0, 0, 0.01), normal=np.array([0.0, 0.0, 2.0]),
                            impedance=hapticd.Impedance(stiffness=1000, damping=1))
    assert isinstance(wall.normal, np.ndarray) and wall.normal.dtype == np.float64
    np.testing.assert_array_equal(wall.normal, [0, 0, 2])
    assert wall.impedance.stiffness == 1000.0
    assert wall == hapticd.WallSpec(point=[0, 0, 0.01], normal=[0, 0, 2],
                                    impedance=hapticd.Impedance(stiffness=1000, damping=1))
    assert wall != hapticd.WallSpec()
    assert "normal=array([0., 0., 2.])" in repr(wall)
    duplicate = copy.deepcopy(wall)
    duplicate.point = (1, 2, 3)
    np.testing.assert_array_equal(wall.point, [0, 0, 0.01])


def test_an_unknown_field_or_a_wrong_shape_is_refused_by_name():
    with pytest.raises(TypeError, match=r"WallSpec\(\) has no field 'nromal'; its fields: point, normal"):
        hapticd.WallSpec(nromal=(0, 0, 1))
    with pytest.raises(TypeError, match=r"WallSpec.normal: cannot take \(1, 2\)"):
        hapticd.WallSpec(normal=(1, 2))
    with pytest.raises(TypeError, match=r"SphereSpec.radius: cannot take 'big'"):
        hapticd.SphereSpec(radius="big")
    with pytest.raises(ValueError, match=r"MeshSpec.vertices: expected an \(N, 3\) array, got shape \(2, 2\)"):
        hapticd.MeshSpec(vertices=[[0, 0], [1, 1]])
    with pytest.raises(ValueError, match=r"MeshSpec.indices\[1\]: -1 is not a vertex index"):
        hapticd.MeshSpec(indices=[0, -1, 2])
    with pytest.raises(ValueError, match=r"ClientConfig.rpc_timeout: -1.0+ s is not a duration"):
        hapticd.ClientConfig(rpc_timeout=-1)


def test_arrays_round_trip_through_meshes_fields_and_profiles():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float32)
    mesh = hapticd.MeshSpec(vertices=vertices, indices=np.array([[0, 2, 1], [0, 1, 3]]))
    np.testing.assert_array_equal(mesh.vertices, vertices)
    assert mesh.vertices.shape == (4, 3)
    np.testing.assert_array_equal(mesh.indices, [0, 2, 1, 0, 1, 3])
    assert mesh.indices.dtype == np.uint32

    linear = hapticd.LinearFieldSpec(jacobian=-10 * np.eye(3), radius=0.1)
    np.testing.assert_array_equal(linear.jacobian, -10 * np.eye(3))
    with pytest.raises(ValueError, match=r"expected a \(3, 3\) array, got 2 rows"):
        linear.jacobian = np.zeros((2, 3))

    recorded = hapticd.OperatorInput.push_recorded(np.ones((5, 3)), 0.01, repeat=True)
    assert recorded.mode == hapticd.OperatorInput.Mode.PUSH
    assert recorded.profile.shape == hapticd.OperatorInput.Profile.Shape.RECORDED
    assert recorded.profile.samples.shape == (5, 3)


def test_operator_inputs_and_enums_read_as_in_cpp():
    follow = hapticd.OperatorInput.follow((0, 0, 0.01), 200.0, 2.0)
    assert follow.mode == hapticd.OperatorInput.Mode.FOLLOW
    np.testing.assert_array_equal(follow.target, [0, 0, 0.01])
    line = hapticd.OperatorInput.follow_line((0, 0, 0), (0, 0, -0.01), 2.0,
                                             hapticd.OperatorInput.Grip.TIGHT)
    assert line.path.shape == hapticd.OperatorInput.Path.Shape.LINE
    assert line.path.duration_s == 2.0
    assert hapticd.OperatorInput.release().mode == hapticd.OperatorInput.Mode.RELEASE
    assert int(hapticd.StateFlag.FORCE_FAULT) == 2
    assert hapticd.Distance(kind=hapticd.Distance.Kind.PLANE).kind == hapticd.Distance.Kind.PLANE
    pose = hapticd.Pose(orientation=(0.0, 1.0, 0.0, 0.0))
    np.testing.assert_array_equal(pose.orientation, [0, 1, 0, 0])  # (w, x, y, z)


def test_federation_stats_are_read_only_results_with_cpp_s_defaults():
    coupling = hapticd.CouplingStats()
    assert coupling.kind == hapticd.CouplingStats.Kind.TOOL
    assert (coupling.port, coupling.remote, coupling.mass) == (0, 0, 0)
    assert coupling.injected_j == coupling.reservoir_j == 0.0
    assert hapticd.CouplingStats.Kind.MASS.name == "MASS"
    assert hapticd.FederationStats().couplings == []
    assert "reservoir_j" in hapticd.CouplingStats._fields
    with pytest.raises(AttributeError):
        coupling.reservoir_j = 1.0  # the server's figures, not the caller's


def test_orientation_specs_take_quaternions_and_laws_and_go_into_scenes():
    spring = hapticd.OrientationSpringSpec(target=(0.5, 0.5, -0.5, 0.5), stiffness=0.8,
                                           damping=0.02, max_torque=0.3,
                                           law=hapticd.ImpedanceLaw.EXACT_ZOH)
    np.testing.assert_array_equal(spring.target, [0.5, 0.5, -0.5, 0.5])  # (w, x, y, z)
    assert (spring.stiffness, spring.damping, spring.max_torque) == (0.8, 0.02, 0.3)
    assert spring.law == hapticd.ImpedanceLaw.EXACT_ZOH
    np.testing.assert_array_equal(hapticd.OrientationSpringSpec().target, [1, 0, 0, 0])
    assert hapticd.OrientationSpringSpec().law == hapticd.ImpedanceLaw.VELOCITY
    detent = hapticd.OrientationDetentSpec(target=(0, 1, 0, 0), depth=0.01, radius=0.2,
                                           rim_height=0.003, rim_width=0.1, damping=0.004)
    assert hapticd.OrientationDetentSpec._fields == ("target", "depth", "radius", "rim_height",
                                                     "rim_width", "damping", "across_sites")
    assert copy.deepcopy(detent) == detent and copy.deepcopy(spring) == spring
    assert detent != hapticd.OrientationDetentSpec(target=(0, 1, 0, 0), depth=0.01)
    with pytest.raises(TypeError, match=r"OrientationSpringSpec.target: cannot take \(1, 0, 0\)"):
        hapticd.OrientationSpringSpec(target=(1, 0, 0))

    scene = hapticd.SceneSpec(fields=[spring, detent])
    assert scene.fields == [spring, detent]  # back out of the C++ variant as the same specs
    text = hapticd.scene_json(scene)
    assert '"orientation_spring"' in text and '"orientation_detent"' in text
    assert '"EXACT_ZOH"' in text and '"max_torque": 0.3' in text


SPEC_TYPES = [hapticd.WallSpec, hapticd.SphereSpec, hapticd.BoxSpec, hapticd.CapsuleSpec,
              hapticd.TangentPlaneSpec, hapticd.MeshSpec, hapticd.SpringFieldSpec,
              hapticd.DistanceSpringSpec, hapticd.PotentialFieldSpec, hapticd.LinearFieldSpec,
              hapticd.ViscousFieldSpec, hapticd.DetentFieldSpec, hapticd.OrientationSpringSpec,
              hapticd.OrientationDetentSpec]


@pytest.mark.parametrize("spec_type", SPEC_TYPES, ids=lambda t: t.__name__)
def test_every_spec_has_across_sites_off_by_default(spec_type):
    assert "across_sites" in spec_type._fields
    assert spec_type().across_sites is False
    spec = spec_type(across_sites=True)
    assert spec.across_sites is True and spec != spec_type()
    assert "across_sites=True" in repr(spec)
    assert copy.deepcopy(spec) == spec


def test_across_sites_goes_into_scenes_and_scene_files():
    sphere = hapticd.SphereSpec(radius=0.02, shared=True, across_sites=True)
    viscous = hapticd.ViscousFieldSpec(damping=2.0, across_sites=True)
    scene = hapticd.SceneSpec(objects=[sphere, hapticd.SphereSpec(radius=0.01)], fields=[viscous])
    assert scene.objects[0].across_sites and not scene.objects[1].across_sites
    assert scene.fields == [viscous]  # back out of the C++ variant with the flag
    text = hapticd.scene_json(scene)
    assert text.count('"across_sites": true') == 2 and '"shared": true' in text


def test_scene_json_writes_a_scene_file():
    scene = hapticd.SceneSpec(
        objects=[hapticd.SphereSpec(center=(0, 0, 0.05), radius=0.02,
                                    impedance=hapticd.Impedance(stiffness=500))],
        fields=[hapticd.ViscousFieldSpec(damping=2.0)])
    text = hapticd.scene_json(scene)
    assert '"sphere"' in text and '"viscous"' in text
    with pytest.raises(hapticd.InvalidArgumentError, match="radius"):
        hapticd.scene_json(hapticd.SceneSpec(objects=[hapticd.SphereSpec(radius=-1)]))


def test_classes_print_as_the_package_s():
    assert hapticd.WallSpec.__module__ == "hapticd"
    assert hapticd.Client.__module__ == "hapticd"
    assert issubclass(hapticd.InvalidArgumentError, hapticd.Error)
    assert issubclass(hapticd.Error, RuntimeError)
    assert hapticd.API_VERSION >= 1
