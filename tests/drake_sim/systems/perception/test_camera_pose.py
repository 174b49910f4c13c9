"""drake_sim.systems.perception.camera_pose: CameraPoseFromPitch gives the camera's pose over
the ground that the plant's kinematics give for the robot leaning on its wheels. (The course
diagram's use of it is in tests/diagrams/test_walle.py.)"""

import math

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import MultibodyPlant

import drake_sim.systems.perception.camera_pose as mut
from drake_sim.robots.walle import BODY_LINK, CAMERA_OPTICAL_FRAME, add_walle, default_robot_file
from drake_sim.robots.walle_params import load_walle_params
from drake_sim.systems.perception.line_detection import camera_pose_over_ground

robot = load_walle_params(default_robot_file())


@pytest.fixture(scope="module")
def plant():
    plant = MultibodyPlant(time_step=0.0)
    add_walle(plant, robot)
    plant.Finalize()
    return plant


def _on_its_wheels(x, y, yaw, pitch) -> RigidTransform:
    """X_WB of the body leaning ``pitch`` (rad) about its axle, whose midpoint is at (x, y) a
    wheel radius above the floor, heading ``yaw`` (rad)."""
    R_WB = RollPitchYaw(0.0, pitch, yaw).ToRotationMatrix()
    p_WA = np.array([x, y, robot.wheel.radius])
    return RigidTransform(R_WB, p_WA - R_WB @ np.array([0.0, 0.0, robot.axle_z]))


def _X_BC(plant, context):
    body = plant.GetBodyByName(BODY_LINK)
    return plant.CalcRelativeTransform(
        context, body.body_frame(), plant.GetFrameByName(CAMERA_OPTICAL_FRAME)
    )


def test_ports():
    dut = mut.CameraPoseFromPitch(robot=robot, X_BC=RigidTransform())
    assert dut.get_input_port().get_name() == "pitch_estimate"
    assert dut.get_input_port().size() == 2
    assert dut.get_output_port().get_name() == "camera_pose"


@pytest.mark.parametrize("pitch", [0.0, 6.0, -10.0])
def test_pose_from_pitch_matches_the_plant(plant, pitch):
    """Anywhere on the floor, any heading: X_GC is the plant's for that lean."""
    context = plant.CreateDefaultContext()
    X_WB = _on_its_wheels(0.7, -0.3, math.radians(35.0), math.radians(pitch))
    plant.SetFreeBodyPose(context, plant.GetBodyByName(BODY_LINK), X_WB)
    X_BC = _X_BC(plant, context)
    dut = mut.CameraPoseFromPitch(robot=robot, X_BC=X_BC)
    dut_context = dut.CreateDefaultContext()
    dut.get_input_port().FixValue(dut_context, [math.radians(pitch), 0.7])  # rate ignored
    X_GC = dut.get_output_port().Eval(dut_context)
    assert X_GC.IsNearlyEqualTo(camera_pose_over_ground(X_WB, X_BC), 1e-9)
    assert X_GC.IsNearlyEqualTo(dut.pose(math.radians(pitch)), 0.0)
    assert X_GC.translation()[2] == pytest.approx(0.35, abs=0.02)  # config/walle.yaml's mount.


def test_leaning_forward_lowers_the_camera_and_tilts_it_down(plant):
    dut = mut.CameraPoseFromPitch(robot=robot, X_BC=_X_BC(plant, plant.CreateDefaultContext()))
    upright, forward = dut.pose(0.0), dut.pose(math.radians(10.0))
    assert forward.translation()[2] < upright.translation()[2]
    assert forward.translation()[0] > upright.translation()[0]  # moved ahead with the lean
    angle = (upright.rotation().inverse() @ forward.rotation()).ToAngleAxis().angle()
    assert angle == pytest.approx(math.radians(10.0))
