"""``urdf_model``: a robot's xacro rendered for its parameters, and added under any name."""

import pytest
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

import drake_sim.robots.urdf_model as mut
from drake_sim.robots.ddrive import ROBOT_XACRO, default_robot_file
from drake_sim.robots.ddrive_params import load_robot_params


@pytest.fixture(scope="module")
def params():
    return load_robot_params(default_robot_file())


def test_render_robot_urdf_is_cached_per_parameter_set(params):
    urdf = mut.render_robot_urdf(ROBOT_XACRO, "ddrive", params)
    assert urdf.is_file() and '<robot name="ddrive"' in urdf.read_text()
    assert mut.render_robot_urdf(ROBOT_XACRO, "ddrive", params) == urdf
    bigger = mut.render_robot_urdf(ROBOT_XACRO, "ddrive", params.scaled(length=1.5))
    assert bigger != urdf


def test_add_robot_urdf_names_the_model_and_refuses_a_second_of_that_name(params):
    urdf = mut.render_robot_urdf(ROBOT_XACRO, "ddrive", params)
    plant, _ = AddMultibodyPlantSceneGraph(DiagramBuilder(), time_step=0.0)
    first = mut.add_robot_urdf(plant, urdf, "ddrive", "left")
    second = mut.add_robot_urdf(plant, urdf, "ddrive", "right")
    assert plant.GetModelInstanceName(first) == "left"
    assert plant.GetModelInstanceName(second) == "right"
    with pytest.raises(RuntimeError):
        mut.add_robot_urdf(plant, urdf, "ddrive", "left")
