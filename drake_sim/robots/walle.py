"""Wall-E's models: the full robot (its xacro rendered and added to a plant) and the reduced
planar model its balance controllers are designed on.

The reduced model is the classic wheeled inverted pendulum in the robot's sagittal plane, as a
small continuous-time ``MultibodyPlant``:

* an *axle* body on a prismatic joint along world x (coordinate ``s``, m, the distance rolled),
  carrying both wheels' mass plus their spin inertia seen through the radius,
  ``2 m_w + 2 J_w / r^2`` with ``J_w = m_w r^2 / 2`` (rolling without slip: a wheel turns at
  ``s_dot / r`` relative to the world);
* the *body* (a solid box of the body's mass and size, centre of mass ``com_height`` above
  the axle) on a revolute joint about y (coordinate ``theta``, rad, positive leaning forward).

The motors apply a torque ``tau`` between the body and the wheels. Its virtual work
``tau (ds / r - dtheta)`` gives the generalized forces ``[tau / r, -tau]``: the wheels push
the robot forward while the body is turned backward. Both wheels act together, so ``tau`` is
their sum. Drake's ``Linearize`` about upright at rest gives ``x_dot = A x + B tau`` with
``x = [s, theta, s_dot, theta_dot]``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from pydrake.math import RigidTransform
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import (
    FixedOffsetFrame,
    ModelInstanceIndex,
    PrismaticJoint,
    RevoluteJoint,
    SpatialInertia,
)
from pydrake.systems.framework import OutputPortSelection
from pydrake.systems.primitives import Linearize

from drake_sim.base.resources import config_dir, models_dir
from drake_sim.robots.urdf_model import add_robot_urdf, render_robot_urdf
from drake_sim.robots.walle_params import WalleParams

ROBOT_XACRO = "walle/walle.urdf.xacro"
"""The robot's xacro, relative to ``models/``."""
SOLID_MACROS = "ddrive/macros.xacro"
"""The shared solid-link macros the xacro includes, relative to ``models/``."""

BODY_LINK = "base_link"
LEFT_WHEEL_JOINT = "left_wheel_joint"
RIGHT_WHEEL_JOINT = "right_wheel_joint"
WHEEL_JOINTS = (LEFT_WHEEL_JOINT, RIGHT_WHEEL_JOINT)
"""In the order of the plant's actuation input: [left, right]."""
IMU_LINK = "imu_link"
CAMERA_LINK = "camera_link"
"""The camera's optical centre; x along the optical axis, y left, z up (ROS body axes)."""
CAMERA_OPTICAL_FRAME = "camera_optical_frame"
"""The camera's optical centre; z along the optical axis, x right, y down: Drake's camera
frame C (``RgbdSensor``) and REP 103's optical frame. Attach a camera here with X_PC = I."""
CASTER_LINKS = ("front_caster", "rear_caster")
"""The support casters, present only when the robot is built with ``support=True``."""

# The planar model's state layout.
S, THETA, S_DOT, THETA_DOT = range(4)


def default_robot_file() -> Path:
    """Returns ``config/walle.yaml``."""
    return config_dir() / "walle.yaml"


def robot_urdf(params: WalleParams, *, support: bool = False) -> Path:
    """Renders Wall-E's URDF for ``params`` (cached) and returns its path.

    Args:
        params: the robot's dimensions; written as YAML beside the cache and handed to the
            xacro, which reads them with ``xacro.load_yaml``.
        support: the "follow" variant, with support casters front and rear.
    """
    return render_robot_urdf(
        ROBOT_XACRO,
        "walle",
        params,
        support="true" if support else "false",
        # Named here so that the cache key covers the shared macros too.
        solid_macros=str(models_dir() / SOLID_MACROS),
    )


def add_walle(
    plant: MultibodyPlant, params: WalleParams, *, name: str = "walle", support: bool = False
) -> ModelInstanceIndex:
    """Adds Wall-E to ``plant`` as a free body (not welded) and returns its model instance.

    Its two actuators are ``left_wheel_motor`` and ``right_wheel_motor``, in that order.
    """
    return add_robot_urdf(plant, robot_urdf(params, support=support), "walle", name)


def make_planar_model(params: WalleParams) -> MultibodyPlant:
    """Builds the reduced planar model (see the module's docstring), finalised, continuous.

    Its actuation input is ``[force on s (N), torque on theta (N m)]``; a wheel torque ``tau``
    is ``[tau / r, -tau]`` there (``planar_wheel_torque_map``).
    """
    b, w = params.body, params.wheel
    plant = MultibodyPlant(time_step=0.0)
    wheels_mass = 2 * w.mass + 2 * (0.5 * w.mass * w.radius**2) / w.radius**2
    # The axle body only translates: the shape of its inertia does not matter.
    axle = plant.AddRigidBody("axle", SpatialInertia.SolidSphereWithMass(wheels_mass, w.radius))
    body = plant.AddRigidBody(
        "body", SpatialInertia.SolidBoxWithMass(b.mass, b.length, b.width, b.height)
    )
    axle_on_body = plant.AddFrame(
        FixedOffsetFrame("axle_on_body", body.body_frame(), RigidTransform([0, 0, params.axle_z]))
    )
    s = plant.AddJoint(PrismaticJoint("s", plant.world_frame(), axle.body_frame(), [1, 0, 0]))
    theta = plant.AddJoint(RevoluteJoint("theta", axle.body_frame(), axle_on_body, [0, 1, 0]))
    for joint in (s, theta):
        plant.AddJointActuator(joint.name(), joint)
    plant.Finalize()
    return plant


def planar_wheel_torque_map(params: WalleParams) -> np.ndarray:
    """The 2 x 1 map from the wheels' total torque (N m) to the planar model's actuation."""
    return np.array([[1.0 / params.wheel.radius], [-1.0]])


def linearize_upright(params: WalleParams) -> tuple[np.ndarray, np.ndarray]:
    """Linearises the planar model about upright at rest.

    Returns:
        ``(A, B)``: ``x_dot = A x + B tau`` for ``x = [s, theta, s_dot, theta_dot]`` (m, rad,
        m/s, rad/s; index with ``S``, ``THETA``, ``S_DOT``, ``THETA_DOT``) and ``tau`` the
        wheels' total torque, N m. A is 4 x 4, B 4 x 1.
    """
    plant = make_planar_model(params)
    context = plant.CreateDefaultContext()
    plant.get_actuation_input_port().FixValue(context, np.zeros(2))
    linear = Linearize(
        plant,
        context,
        input_port_index=plant.get_actuation_input_port().get_index(),
        output_port_index=OutputPortSelection.kNoOutput,
    )
    return np.array(linear.A()), np.array(linear.B()) @ planar_wheel_torque_map(params)
