"""Meshcat display of odometry against ground truth (RViz's odometry display)."""

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.geometry import Cylinder, Meshcat, Rgba
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.systems.framework import LeafSystem

ODOMETRY_COLOR = Rgba(0.1, 0.4, 1.0, 1.0)
TRUTH_COLOR = Rgba(0.1, 0.8, 0.2, 1.0)


class TrailVisualizer(LeafSystem):
    """Draws the trail of the odometry and of the ground truth, and an arrow at the odometry's
    current pose, in Meshcat under ``/odometry``.

    .. pydrake_system::

        name: TrailVisualizer
        input_ports:
        - odometry_pose
        - true_pose

    Both inputs are ``[x, y, yaw]``. The trails are sampled every ``period`` seconds into
    abstract state and keep the last ``max_points`` samples (every sample is sent to the
    browser at each redraw); with a recording running, the arrow's motion is recorded too.
    """

    def __init__(
        self, *, meshcat: Meshcat, period: float, height: float = 0.01, max_points: int = 3000
    ):
        super().__init__()
        self._meshcat = meshcat
        self._height = height
        self._max_points = max_points
        self._odometry = self.DeclareVectorInputPort("odometry_pose", 3)
        self._truth = self.DeclareVectorInputPort("true_pose", 3)
        self._trails = self.DeclareAbstractState(AbstractValue.Make(np.zeros((0, 6))))
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._sample)
        self.DeclarePeriodicPublishEvent(period, 0.0, self._draw)
        self.DeclareForcedPublishEvent(self._draw)
        meshcat.SetObject("/odometry/arrow/shaft", Cylinder(0.012, 0.3), ODOMETRY_COLOR)
        meshcat.SetTransform(
            "/odometry/arrow/shaft", RigidTransform(RollPitchYaw(0, np.pi / 2, 0), [0.15, 0, 0])
        )

    def _sample(self, context, state):
        trails = context.get_abstract_state(self._trails).get_value()
        row = np.concatenate([self._odometry.Eval(context), self._truth.Eval(context)])
        trails = np.vstack([trails[-(self._max_points - 1) :], row])
        state.get_mutable_abstract_state(self._trails).set_value(trails)

    def _draw(self, context):
        trails = context.get_abstract_state(self._trails).get_value()
        if len(trails) < 2:
            return
        z = np.full(len(trails), self._height)
        for name, cols, color in (
            ("estimate", (0, 1), ODOMETRY_COLOR),
            ("truth", (3, 4), TRUTH_COLOR),
        ):
            vertices = np.vstack([trails[:, cols[0]], trails[:, cols[1]], z])
            self._meshcat.SetLine(f"/odometry/{name}_trail", vertices, 3.0, color)
        x, y, yaw = trails[-1, :3]
        X = RigidTransform(RollPitchYaw(0, 0, yaw), [x, y, self._height])
        self._meshcat.SetTransform("/odometry/arrow", X, time_in_recording=context.get_time())
