"""Plan: timing within limits, sampling, save/load, validation against a scene, plot, replay."""

import numpy as np
import pytest
from pydrake.math import RigidTransform

import planning.plan as mut
from planning import ErrorCode, PlanningError, PlanningScene

V_MAX = np.array([2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61])
A_MAX = np.array([15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0])
READY = np.array([0.0, -0.785398, 0.0, -2.356194, 0.0, 1.570796, 0.785398])
EXTENDED = np.array([0.0, 0.6, 0.0, -0.9, 0.0, 1.5, 0.785398])


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


@pytest.fixture
def dut(scene):
    middle = 0.5 * (READY + EXTENDED) + [0.3, 0, 0, 0, 0, 0, 0]
    return mut.Plan(
        waypoints=[READY, middle, EXTENDED],
        max_velocity=V_MAX,
        max_acceleration=A_MAX,
        scene=mut.describe_scene(scene),
        info={"planner": "test"},
    )


def test_sample_passes_through_waypoints(dut):
    for t, q in zip(dut.times, dut.waypoints, strict=True):
        np.testing.assert_allclose(dut.sample(t)[0], q, atol=1e-7)
    for t in dut.stop_times:
        np.testing.assert_allclose(dut.sample(t)[1], 0.0, atol=1e-9)
    # The corner (turning by 0.58 rad) is blended: the arm does not stop there.
    np.testing.assert_allclose(dut.stop_times, dut.times[[0, -1]])
    assert np.linalg.norm(dut.sample(dut.times[1])[1]) > 0.2
    np.testing.assert_allclose(dut.sample(-1.0)[0], READY)
    np.testing.assert_allclose(dut.sample(dut.duration + 1.0)[0], EXTENDED)


def test_limits_hold_and_one_joint_reaches_them(dut):
    ts = np.linspace(0.0, dut.duration, 2001)
    v = np.array([dut.sample(t)[1] for t in ts])
    a = np.array([dut.sample(t)[2] for t in ts])
    assert np.all(np.abs(v) <= V_MAX + 1e-9)
    assert np.all(np.abs(a) <= A_MAX + 1e-9)
    assert np.max(np.abs(v) / V_MAX) > 0.99 or np.max(np.abs(a) / A_MAX) > 0.99
    # Velocity is the derivative of position.
    q = np.array([dut.sample(t)[0] for t in ts])
    np.testing.assert_allclose(np.gradient(q, ts, axis=0), v, atol=0.05)


def test_scaling_slows_down(dut):
    slow = mut.Plan(dut.waypoints, 0.5 * V_MAX, 0.25 * A_MAX, 0.5, 0.25)
    assert slow.duration == pytest.approx(2.0 * dut.duration)


def test_save_and_load_equal(dut, tmp_path):
    dut.save(tmp_path / "plan.json")
    loaded = mut.Plan.load(tmp_path / "plan.json")
    assert loaded == dut
    np.testing.assert_array_equal(loaded.times, dut.times)
    assert loaded.info == {"planner": "test"}
    assert loaded.robot["joints"][0] == "panda_joint1"


def test_load_rejects_other_files(tmp_path):
    (tmp_path / "x.json").write_text('{"format": "other"}')
    with pytest.raises(PlanningError, match="x.json: format") as error:
        mut.Plan.load(tmp_path / "x.json")
    assert error.value.code is ErrorCode.INVALID_MOTION_PLAN


def test_validate_and_scene_matching(dut, scene):
    assert dut.scene_matches(scene)
    dut.validate(scene)
    X_WE = RigidTransform([0.55, 0.0, 0.45])
    scene.add_box("crate", [0.3, 0.3, 0.3], X_WE)
    try:
        assert not dut.scene_matches(scene)
        with pytest.raises(PlanningError) as e:
            dut.validate(scene)
        assert e.value.code == ErrorCode.INVALID_MOTION_PLAN
        assert "crate" in e.value.message
    finally:
        scene.remove_object("crate")


def test_plot_writes_a_png(dut, tmp_path):
    pytest.importorskip("matplotlib")
    dut.plot(tmp_path / "plan.png")
    assert (tmp_path / "plan.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_replay_without_meshcat_is_a_no_op(dut, scene, monkeypatch):
    """Nothing is published, nothing waits (even in real time), the scene is untouched."""
    published, slept = [], []
    monkeypatch.setattr(scene, "publish", published.append)
    monkeypatch.setattr(mut.time, "sleep", slept.append)
    version, fingers = scene.version, scene.finger_positions
    assert dut.replay(scene) is None
    assert published == [] and slept == []
    assert scene.version == version
    np.testing.assert_array_equal(scene.finger_positions, fingers)


def test_replay_in_meshcat(dut, monkeypatch):
    from pydrake.geometry import Meshcat

    meshcat = Meshcat()
    shown = PlanningScene(meshcat=meshcat)
    fingers = [0.01, 0.01]
    shown.finger_positions = fingers
    published = []

    def publish(q):
        published.append((np.array(q), shown.finger_positions))
        PlanningScene.publish(shown, q)

    monkeypatch.setattr(shown, "publish", publish)
    dut.replay(shown, dt=0.2, realtime=False)
    assert meshcat.HasPath("planning/objects/world/table")
    # One frame every dt from the start to the end, with the plan's fingers; then the scene's.
    ts, qs = dut.sample_many(0.2)
    assert len(published) == len(ts)
    np.testing.assert_allclose([q for q, _ in published], qs)
    np.testing.assert_allclose(published[-1][0], EXTENDED, atol=1e-12)
    for _, shown_fingers in published:
        np.testing.assert_array_equal(shown_fingers, dut.finger_positions)
    np.testing.assert_array_equal(shown.finger_positions, fingers)


def arc_path(n=41, step=0.015, curvature=0.5):
    """A nearly straight joint path like a Cartesian one: n waypoints step rad apart on an arc
    of the given curvature (1/rad) in the plane of joints 1 and 2, from READY."""
    angle = step * curvature * np.arange(n - 1)
    steps = np.zeros((n - 1, 7))
    steps[:, 1], steps[:, 3] = step * np.cos(angle), step * np.sin(angle)
    return READY + np.vstack([np.zeros(7), np.cumsum(steps, axis=0)])


def distance_to_polyline(q, waypoints):
    a, d = waypoints[:-1], np.diff(waypoints, axis=0)
    lam = np.clip(np.einsum("kj,kj->k", q - a, d) / np.einsum("kj,kj->k", d, d), 0.0, 1.0)
    return np.min(np.linalg.norm(q - a - lam[:, None] * d, axis=1))


def test_dense_path_is_timed_without_stops_within_limits_and_tolerance():
    path = arc_path()
    dut = mut.Plan(path, V_MAX, A_MAX)
    stopping = mut.Plan(path, V_MAX, A_MAX, timing=mut.RetimeOptions(method="rest_to_rest"))
    assert len(dut.stop_times) == 2
    assert dut.duration < 0.3 * stopping.duration
    ts = np.linspace(0.0, dut.duration, 5001)
    q, v, a = (np.array(x) for x in zip(*(dut.sample(t) for t in ts), strict=True))
    assert np.all(np.abs(v) <= V_MAX * (1 + 1e-6))
    assert np.all(np.abs(a) <= A_MAX * (1 + 1e-6))
    assert np.max(np.abs(a) / A_MAX) > 0.9  # near time-optimal: a limit is reached
    np.testing.assert_array_equal(q[0], path[0])
    np.testing.assert_array_equal(q[-1], path[-1])
    np.testing.assert_allclose(v[[0, -1]], 0.0, atol=1e-9)
    np.testing.assert_allclose(np.gradient(q, ts, axis=0), v, atol=0.02)
    deviation = max(distance_to_polyline(x, path) for x in q[::10])
    assert deviation <= dut.timing.path_tolerance
    # The trajectory passes the waypoints, in order, at ``times``.
    assert np.all(np.diff(dut.times) > 0)
    for t, w in zip(dut.times[::8], path[::8], strict=True):
        np.testing.assert_allclose(dut.sample(t)[0], w, atol=1e-4)


def test_sharp_corners_are_stops():
    path = np.vstack([READY, READY + [0.5, 0, 0, 0, 0, 0, 0], READY + [0.5, 1.0, 0, 0, 0, 0, 0]])
    dut = mut.Plan(path, V_MAX, A_MAX)
    np.testing.assert_allclose(dut.stop_times, dut.times)
    np.testing.assert_allclose(dut.sample(dut.times[1])[1], 0.0, atol=1e-9)


def test_timing_is_deterministic_and_survives_save_and_load(tmp_path):
    dut = mut.Plan(arc_path(), V_MAX, A_MAX)
    dut.save(tmp_path / "plan.json")
    loaded = mut.Plan.load(tmp_path / "plan.json")
    assert loaded.timing == dut.timing
    for t in np.linspace(0.0, dut.duration, 7):
        np.testing.assert_array_equal(loaded.sample(t)[0], dut.sample(t)[0])


def test_version_1_files_keep_their_rest_to_rest_timing(dut):
    data = dut.to_dict()
    data["version"] = 1
    del data["timing"]
    old = mut.Plan.from_dict(data)
    assert old.timing.method == "rest_to_rest"
    np.testing.assert_allclose(old.stop_times, old.times)
    data["version"] = 99
    with pytest.raises(PlanningError, match="version 99 is newer"):
        mut.Plan.from_dict(data)


def test_bad_timing_options_are_rejected():
    with pytest.raises(ValueError):
        mut.RetimeOptions(method="fastest")
    # The path's ends turn by pi: a corner angle of pi would leave no stop, and no timing.
    with pytest.raises(ValueError, match="max_corner_angle"):
        mut.RetimeOptions(max_corner_angle=np.pi)


def test_blended_corner_stays_near_the_checked_path(dut):
    ts = np.linspace(0.0, dut.duration, 3001)
    deviation = max(distance_to_polyline(dut.sample(t)[0], dut.waypoints) for t in ts)
    assert deviation <= dut.timing.path_tolerance
    assert len(dut._timing.smoothed_paths(0.01)) == 1
    rest_to_rest = mut.Plan(dut.waypoints, V_MAX, A_MAX, timing=mut.RetimeOptions("rest_to_rest"))
    assert dut.duration < rest_to_rest.duration
