"""diagrams.planning_station: make_planning_station joins a started interface to the station of
a pick-and-place scenario (its mode, or the ``mode`` argument's), with the state at the
scenario's initial configuration and a planning scene holding the scene's objects and
``place_position``; make_planning_scene builds that scene."""

import dataclasses as dc

import numpy as np
import pytest

import diagrams.planning_station as mut
from diagrams.pickplace_scenario import load_pickplace_scenario
from diagrams.scene_boxes import box_pose
from drake_sim.base.errors import ConfigError
from planning.model.planning_model import finger_defaults, named_configurations


@pytest.fixture(scope="module")
def scenario():
    return load_pickplace_scenario()  # the shipped one, in physics mode


@pytest.fixture(scope="module")
def dut(scenario):
    """The shipped scenario, started in "transport" (not the default "ready"), kinematic."""
    return mut.make_planning_station(
        dc.replace(scenario, initial_configuration="transport"), mode="kinematic"
    )


def _initial_q(scenario, name: str) -> np.ndarray:
    model = scenario.robot.model
    return np.array([*named_configurations(model)[name], *finger_defaults(model)])


def test_mode_argument_overrides_the_scenario(scenario, dut):
    assert scenario.mode == "physics"  # the argument did not change the caller's scenario
    assert dut.kinematic
    assert dut.simulator.get_system().get_name() == "planning_station_kinematic"
    station = dut.simulator.get_system().GetSubsystemByName("station")
    assert station.HasInputPort("object.position_command")


def test_state_starts_at_the_initial_configuration(scenario, dut):
    expected = _initial_q(scenario, "transport")
    assert dut.time == 0.0
    np.testing.assert_allclose(dut.state.q_full, expected, atol=1e-12)
    x = dut.read_state()
    np.testing.assert_allclose(x[:9], expected, atol=1e-12)
    np.testing.assert_allclose(x[9:], 0.0, atol=1e-12)


def test_planning_scene_holds_the_scene(scenario, dut):
    spec = scenario.scene
    objects = dut.scene.world_objects
    assert sorted(objects) == ["object", "obstacle", "table"]
    for name in objects:
        box = getattr(spec, name)
        assert objects[name].shape == "box"
        np.testing.assert_allclose(objects[name].size, box.size)
        assert objects[name].X_PO.IsNearlyEqualTo(box_pose(box), 1e-12)
    np.testing.assert_allclose(dut.scene.place_position, spec.place.position)
    assert dut.state.scene is dut.scene
    # The simulated object starts where the planning scene has it.
    assert dut.object_pose().IsNearlyEqualTo(objects["object"].X_PO, 1e-9)


def test_scenario_mode_by_default(scenario):
    dut = mut.make_planning_station(scenario)
    assert not dut.kinematic
    assert dut.simulator.get_system().get_name() == "planning_station_physics"
    np.testing.assert_allclose(dut.read_state()[:9], _initial_q(scenario, "ready"), atol=1e-9)


def test_bad_mode_is_a_config_error(scenario):
    with pytest.raises(ConfigError, match="mode 'hardware'"):
        mut.make_planning_station(scenario, mode="hardware")


def test_make_planning_scene_without_place_or_obstacle(scenario):
    spec = dc.replace(scenario.scene, place=None, obstacle=None)
    dut = mut.make_planning_scene(dc.replace(scenario, scene=spec))
    assert sorted(dut.world_objects) == ["object", "table"]
    assert dut.place_position is None
    assert dut.config is scenario.robot
