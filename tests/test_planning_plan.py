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


def test_sample_passes_through_waypoints_at_rest(dut):
    for t, q in zip(dut.times, dut.waypoints, strict=True):
        q_t, v_t, _ = dut.sample(t)
        np.testing.assert_allclose(q_t, q, atol=1e-9)
        np.testing.assert_allclose(v_t, 0.0, atol=1e-9)
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
    with pytest.raises(ValueError):
        mut.Plan.load(tmp_path / "x.json")


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


def test_replay_without_meshcat_is_a_no_op(dut, scene):
    dut.replay(scene, realtime=False)


def test_replay_in_meshcat(dut):
    from pydrake.geometry import Meshcat

    meshcat = Meshcat()
    shown = PlanningScene(meshcat=meshcat)
    dut.replay(shown, dt=0.2, realtime=False)
    assert meshcat.HasPath("planning/objects/world/table")
