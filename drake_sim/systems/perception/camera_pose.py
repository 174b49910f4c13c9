"""The line camera's pose over the ground from a balancing robot's estimated pitch.

A camera on a two-wheeled robot that balances tilts with the body, so the ``LineDetector``'s
ground projection needs the camera's pose over the ground frame G at the current lean (the
follow variant, upright on its casters, uses a fixed pose instead). ``CameraPoseFromPitch``
turns the ``PitchEstimator``'s estimate into that pose, as ``camera_pose_over_ground`` does for a
body pose.
"""

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.framework import LeafSystem

from drake_sim.robots.walle_params import WalleParams
from drake_sim.systems.perception.line_detection import camera_pose_over_ground


class CameraPoseFromPitch(LeafSystem):
    """The camera's pose X_GC over the robot's ground frame G, from the estimated pitch.

    .. pydrake_system::

        name: CameraPoseFromPitch
        input_ports:
        - pitch_estimate
        output_ports:
        - camera_pose

    ``pitch_estimate`` is ``[theta, theta_dot]`` (rad, rad/s; the ``PitchEstimator``'s);
    ``camera_pose`` the ``RigidTransform`` X_GC for the ``LineDetector``'s ``camera_pose``
    input: the body leans ``theta`` about its axle, whose midpoint is ``wheel.radius`` above
    the floor, and the camera sits at X_BC on the body B.
    """

    def __init__(self, *, robot: WalleParams, X_BC: RigidTransform):
        super().__init__()
        self._X_BC = X_BC
        self._r = robot.wheel.radius
        self._p_BA = np.array([0.0, 0.0, robot.axle_z])
        self._pitch = self.DeclareVectorInputPort("pitch_estimate", 2)
        self.DeclareAbstractOutputPort(
            "camera_pose", lambda: AbstractValue.Make(RigidTransform()), self._calc
        )

    def pose(self, theta: float) -> RigidTransform:
        """X_GC for a lean of ``theta`` (rad, positive forward)."""
        R_WB = RotationMatrix.MakeYRotation(theta)
        X_WB = RigidTransform(R_WB, np.array([0.0, 0.0, self._r]) - R_WB @ self._p_BA)
        return camera_pose_over_ground(X_WB, self._X_BC)

    def _calc(self, context, output):
        output.set_value(self.pose(float(self._pitch.Eval(context)[0])))
