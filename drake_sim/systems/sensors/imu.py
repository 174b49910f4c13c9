"""A simulated inertial measurement unit on one body of a MultibodyPlant.

Built from Drake's C++ systems (``Gyroscope``, ``Accelerometer``, ``RandomSource``, gains and
adders), because Python systems evaluated often dominate the cost of a small simulation: the
IMU costs next to nothing however often its output is read.
"""

import dataclasses as dc

import numpy as np
from pydrake.common import RandomDistribution
from pydrake.math import RigidTransform
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import RigidBody
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import (
    Adder,
    DiscreteTimeIntegrator,
    MatrixGain,
    Multiplexer,
    RandomSource,
)
from pydrake.systems.sensors import Accelerometer, Gyroscope

# Layout of the IMU's output vector.
QUATERNION = slice(0, 4)  # Orientation R_WB as a quaternion [w, x, y, z] (normalise it).
ANGULAR_VELOCITY = slice(4, 7)  # w_WB expressed in B, rad/s.
LINEAR_ACCELERATION = slice(7, 10)  # Specific force (a_WB - g) expressed in B, m/s^2.
IMU_SIZE = 10

GRAVITY_W = np.array([0.0, 0.0, -9.81])  # m/s^2.


@dc.dataclass
class ImuConfig:
    """Noise model of the IMU: standard deviations of white noise (redrawn ``rate`` times a
    second) and of constant biases (drawn once per run)."""

    rate: float = 100.0  # Hz, how often the noise is redrawn.
    orientation_noise: float = 0.002  # Added to each quaternion component (about 2x this, rad).
    angular_velocity_noise: float = 0.01  # rad/s.
    linear_acceleration_noise: float = 0.05  # m/s^2.
    angular_velocity_bias: float = 0.002  # rad/s.
    linear_acceleration_bias: float = 0.02  # m/s^2.


class Imu(Diagram):
    """Orientation, angular velocity and specific force of a body, with seeded noise and bias.

    .. pydrake_system::

        name: Imu
        input_ports:
        - body_poses
        - body_spatial_velocities
        - body_spatial_accelerations
        - plant_state
        output_ports:
        - imu
        - delta_velocity
        - delta_angle

    Connect the inputs to the plant's ports of the same names (``plant_state`` is the plant's
    full state); ``add_imu`` does. The ``imu`` output's layout is given by ``QUATERNION``,
    ``ANGULAR_VELOCITY`` and ``LINEAR_ACCELERATION``, for the sensor frame S at ``X_BS`` on
    the body (S's orientation is taken to be the body's). ``delta_velocity`` is the measured
    specific force integrated at every ``integration_period`` since the start, expressed in S
    (m/s), as many IMUs report it: differencing it gives the velocity change over any interval
    without missing the brief, large accelerations of an impact, which sampling the
    acceleration at a low rate would alias. ``delta_angle`` likewise integrates the measured
    angular velocity (rad, in S): its change over a short interval is the rotation in it.
    The noise is reproducible: seed it with
    ``diagram.SetRandomContext(context, RandomGenerator(seed))``.
    """

    def __init__(
        self,
        *,
        plant: MultibodyPlant,
        body: RigidBody,
        config: ImuConfig,
        p_BS: np.ndarray = np.zeros(3),  # noqa: B008 (an immutable default)
        integration_period: float = 1e-3,
    ):
        super().__init__()
        if not body.is_floating_base_body():
            raise ValueError(f"the IMU's body {body.name()} must be a floating base body")
        builder = DiagramBuilder()
        X_BS = RigidTransform(np.asarray(p_BS, dtype=float))
        gyro = builder.AddNamedSystem("gyroscope", Gyroscope(body, X_BS))
        accel = builder.AddNamedSystem("accelerometer", Accelerometer(body, X_BS, GRAVITY_W))
        # The floating base's quaternion is the first four of its positions.
        select = np.zeros((4, plant.num_multibody_states()))
        select[:, body.floating_positions_start() + np.arange(4)] = np.eye(4)
        orientation = builder.AddNamedSystem("orientation", MatrixGain(select))
        truth = builder.AddNamedSystem("truth", Multiplexer([4, 3, 3]))
        builder.Connect(orientation.get_output_port(), truth.get_input_port(0))
        builder.Connect(gyro.GetOutputPort("measurement"), truth.get_input_port(1))
        builder.Connect(accel.GetOutputPort("measurement"), truth.get_input_port(2))

        c = config
        noise_std = [c.orientation_noise] * 4 + [c.angular_velocity_noise] * 3
        noise_std += [c.linear_acceleration_noise] * 3
        bias_std = [0.0] * 4 + [c.angular_velocity_bias] * 3 + [c.linear_acceleration_bias] * 3
        noise = builder.AddNamedSystem(
            "noise", RandomSource(RandomDistribution.kGaussian, IMU_SIZE, 1.0 / c.rate)
        )
        # Drawn at initialisation and then every 1e9 s (about 30 years): a constant bias.
        bias = builder.AddNamedSystem(
            "bias", RandomSource(RandomDistribution.kGaussian, IMU_SIZE, 1e9)
        )
        noise_gain = builder.AddNamedSystem("noise_gain", MatrixGain(np.diag(noise_std)))
        bias_gain = builder.AddNamedSystem("bias_gain", MatrixGain(np.diag(bias_std)))
        builder.Connect(noise.get_output_port(), noise_gain.get_input_port())
        builder.Connect(bias.get_output_port(), bias_gain.get_input_port())
        measured = builder.AddNamedSystem("measured", Adder(3, IMU_SIZE))
        builder.Connect(truth.get_output_port(), measured.get_input_port(0))
        builder.Connect(noise_gain.get_output_port(), measured.get_input_port(1))
        builder.Connect(bias_gain.get_output_port(), measured.get_input_port(2))

        poses = builder.ExportInput(gyro.GetInputPort("body_poses"), "body_poses")
        builder.ConnectInput(poses, accel.GetInputPort("body_poses"))
        velocities = builder.ExportInput(
            gyro.GetInputPort("body_spatial_velocities"), "body_spatial_velocities"
        )
        builder.ConnectInput(velocities, accel.GetInputPort("body_spatial_velocities"))
        builder.ExportInput(
            accel.GetInputPort("body_spatial_accelerations"), "body_spatial_accelerations"
        )
        builder.ExportInput(orientation.get_input_port(), "plant_state")
        builder.ExportOutput(measured.get_output_port(), "imu")
        for name, part in (
            ("delta_velocity", LINEAR_ACCELERATION),
            ("delta_angle", ANGULAR_VELOCITY),
        ):
            select = np.zeros((3, IMU_SIZE))
            select[:, part] = np.eye(3)
            selected = builder.AddNamedSystem(f"{name}_input", MatrixGain(select))
            integrator = builder.AddNamedSystem(name, DiscreteTimeIntegrator(3, integration_period))
            builder.Connect(measured.get_output_port(), selected.get_input_port())
            builder.Connect(selected.get_output_port(), integrator.get_input_port())
            builder.ExportOutput(integrator.get_output_port(), name)
        builder.BuildInto(self)


def rotation_from_quaternion(q) -> np.ndarray:
    """Returns the 3x3 rotation matrix of the quaternion ``q = [w, x, y, z]`` (normalised
    first; the identity if ``q`` is zero). Plain arithmetic: the controllers call this every
    update, and building Drake's Quaternion and RotationMatrix objects costs 20 times more."""
    w, x, y, z = (float(v) for v in q)
    norm2 = w * w + x * x + y * y + z * z
    if not norm2 > 1e-18:
        return np.eye(3)
    s = 2.0 / norm2
    wx, wy, wz = s * w * x, s * w * y, s * w * z
    xx, xy, xz = s * x * x, s * x * y, s * x * z
    yy, yz, zz = s * y * y, s * y * z, s * z * z
    return np.array(
        [
            [1.0 - yy - zz, xy - wz, xz + wy],
            [xy + wz, 1.0 - xx - zz, yz - wx],
            [xz - wy, yz + wx, 1.0 - xx - yy],
        ]
    )


def rotation_from_imu(imu: np.ndarray) -> np.ndarray:
    """Returns the 3x3 orientation matrix R_WB held in an IMU output vector."""
    return rotation_from_quaternion(imu[QUATERNION])


def add_imu(
    builder: DiagramBuilder,
    plant: MultibodyPlant,
    body: RigidBody,
    config: ImuConfig,
    p_BS: np.ndarray = np.zeros(3),  # noqa: B008 (an immutable default)
) -> Imu:
    """Adds an ``Imu`` at ``p_BS`` on ``body`` (a floating base body of ``plant``), wired to
    the plant, integrating its acceleration at the plant's time step."""
    imu = builder.AddNamedSystem(
        f"imu_{body.name()}",
        Imu(
            plant=plant,
            body=body,
            config=config,
            p_BS=p_BS,
            integration_period=plant.time_step(),
        ),
    )
    builder.Connect(plant.get_body_poses_output_port(), imu.GetInputPort("body_poses"))
    builder.Connect(
        plant.get_body_spatial_velocities_output_port(),
        imu.GetInputPort("body_spatial_velocities"),
    )
    builder.Connect(
        plant.get_body_spatial_accelerations_output_port(),
        imu.GetInputPort("body_spatial_accelerations"),
    )
    builder.Connect(plant.get_state_output_port(), imu.GetInputPort("plant_state"))
    return imu
