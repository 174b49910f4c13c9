"""Cartesian straight-line paths of the end effector by damped least-squares IK steps.

The hand pose is interpolated from X_WE(q_start) to the goal (position linearly, orientation by
slerp) in steps of at most ``max_step`` m and ``max_rotation_step`` rad. Each step is solved by a
few damped Newton iterations on the 6-D pose error from the previous step's joints
(``dq = J^T (J J^T + lambda^2 I)^-1 e``, J the hand's spatial-velocity Jacobian in W), which
keeps the arm on one IK branch; a step's solve is one compiled call (``pose_kernel``: about
15 us, against 0.25 ms through Drake's bindings, measured). A step is accepted
when it converges, stays within joint limits, moves no joint more than ``jump_threshold`` rad,
and the joint-space segment to it is collision-free at ``resolution`` rad. The first step that
fails ends the path; the fraction achieved is reported.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix

from planning.collision.sphere_fk import BatchedKinematics
from planning.paths import densify
from planning.search.pose_kernel import frame_pose, line, newton

_MAX_ITERATIONS = 30
_NO_ROTATION = np.eye(3)  # placeholders of an unused target
_NO_POSITION = np.zeros(3)


@dataclass
class CartesianPath:
    """Waypoints (N, 7) in rad achieved along the line, the fraction in [0, 1], and why it
    stopped ("" when complete)."""

    waypoints: np.ndarray
    fraction: float
    reason: str


def interpolate_pose(X_a: RigidTransform, X_b: RigidTransform, s: float) -> RigidTransform:
    """Pose a fraction s of the way from X_a to X_b (linear position, slerp orientation)."""
    R, p = _line(X_a, X_b, np.array([s]))
    return RigidTransform(RotationMatrix(R[0]), p[0])


def _line(X_a: RigidTransform, X_b: RigidTransform, s: np.ndarray):
    """The poses at the fractions s (K,) of the way from X_a to X_b: rotations (K, 3, 3) by
    slerp of the unit quaternions along the shorter arc, positions (K, 3) linearly."""
    q_a = X_a.rotation().ToQuaternion().wxyz()
    q_b = X_b.rotation().ToQuaternion().wxyz()
    dot = float(q_a @ q_b)
    if dot < 0.0:  # q and -q are one rotation: take the shorter way
        q_b, dot = -q_b, -dot
    s = np.asarray(s, dtype=float)[:, None]
    if dot > 1.0 - 1e-12:
        quat = (1.0 - s) * q_a + s * q_b
    else:
        theta = np.arccos(dot)
        quat = (np.sin((1.0 - s) * theta) * q_a + np.sin(s * theta) * q_b) / np.sin(theta)
    w, x, y, z = (quat / np.linalg.norm(quat, axis=1, keepdims=True)).T
    R = np.empty((len(w), 3, 3))
    R[:, 0] = np.column_stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)])
    R[:, 1] = np.column_stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)])
    R[:, 2] = np.column_stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)])
    p = (1.0 - s) * X_a.translation() + s * X_b.translation()
    return R, p


def cartesian_path(
    scene,
    adapter,
    frame,
    q_start: np.ndarray,
    X_WG: RigidTransform,
    *,
    max_step: float,
    max_rotation_step: float,
    jump_threshold: float,
    resolution: float,
    solver: PoseNewton | None = None,
) -> CartesianPath:
    """Follows the straight line from the frame's pose at q_start to X_WG.

    Args:
        scene: the ``PlanningScene``.
        adapter: ``planning.collision.checker.CheckerAdapter`` on the scene.
        frame: the moving frame E (a plant frame of the Panda).
        q_start: 7 arm joints, rad, collision-free.
        X_WG: goal pose of E in W.
        max_step: largest translation per step, m.
        max_rotation_step: largest rotation per step, rad.
        jump_threshold: largest change of any joint per step, rad.
        resolution: joint-space collision check step, rad.
        solver: the frame's ``PoseNewton`` (made here when None; ``IkSolver.newton`` keeps
            one per frame).
    """
    if solver is None:
        solver = PoseNewton(
            scene.plant, frame, scene.full_q, scene.model.arm_indices, adapter.lower, adapter.upper
        )
    X_WS = solver.pose(q_start)
    distance = np.linalg.norm(X_WG.translation() - X_WS.translation())
    angle = (X_WS.rotation().inverse() @ X_WG.rotation()).ToAngleAxis().angle()
    steps = max(1, int(np.ceil(max(distance / max_step, angle / max_rotation_step))))
    R_targets, p_targets = _line(X_WS, X_WG, np.arange(1, steps + 1) / steps)
    # Every IK step first (one compiled call), then one batched collision check of the line.
    path, status = solver.line(q_start, R_targets, p_targets, jump_threshold)
    reason = ""
    if status == 1:
        reason = "no IK solution near the previous step (joint limit or singularity)"
    elif status == 2:
        reason = f"joint jump above {jump_threshold} rad"
    if len(path) > 1:
        samples, segment = densify(path, resolution)
        free = adapter.configs_free(samples)
        if not free.all():
            first = int(np.argmin(free))
            path = path[: segment[first] + 1]  # up to the step before the colliding segment
            reason = f"collision: {scene.describe_collisions(samples[first])}"
    if reason:
        return CartesianPath(path, (len(path) - 1) / steps, reason)
    return CartesianPath(path, 1.0, "")


class PoseNewton:
    """Damped Newton steps on the pose error of a frame (see the module docstring), one
    compiled call per solve (``planning.search.pose_kernel``: the frame's kinematic chain and
    its exact Jacobian, the error's rotation vector by the log map). Large errors are cut to
    ``pose_kernel._MAX_ERROR`` m / ``_MAX_TURN`` rad per step, so that far targets are
    approached gradually rather than overshot.

    Args:
        plant: the MultibodyPlant.
        frame: the frame E to place.
        full: (q) -> the plant's positions for the 7 arm joints q (the other joints fixed).
        arm: the arm joints' indices among the plant's positions.
        lower, upper: the arm's joint limits, rad.
    """

    def __init__(self, plant, frame, full, arm, lower, upper):
        kinematics = BatchedKinematics(plant, [frame.body().index()])
        self._full = full
        # pose_kernel's frame data but the template (the other joints, read at each call).
        self._fixed = (
            np.asarray(arm, dtype=np.int64),
            *kinematics.arrays(),
            int(kinematics.out[0]),
            np.ascontiguousarray(frame.GetFixedPoseInBodyFrame().GetAsMatrix34()),
            np.ascontiguousarray(lower, dtype=float),
            np.ascontiguousarray(upper, dtype=float),
        )

    def _frame(self, q) -> tuple:
        """pose_kernel's frame data with the plant positions at the arm joints q."""
        return (np.ascontiguousarray(self._full(q), dtype=float), *self._fixed)

    def pose(self, q) -> RigidTransform:
        """X_WE at the arm joints q (7,)."""
        full, _, parent, kind, q_index, terms, body, X_BE, _, _ = self._frame(q)
        T, X = np.empty((len(parent), 3, 4)), np.empty((3, 4))
        frame_pose(full, parent, kind, q_index, terms, body, X_BE, T, X)
        return RigidTransform(X)

    def line(self, q_start, R_targets, p_targets, jump_threshold: float):
        """The joints along a line of poses (``pose_kernel.line``): (path (M, 7) from q_start,
        status: 0 complete, 1 a pose not reached, 2 a joint jump above ``jump_threshold``)."""
        q_start = np.array(q_start, dtype=float).reshape(-1)
        return line(
            q_start,
            self._frame(q_start),
            np.ascontiguousarray(R_targets, dtype=float),
            np.ascontiguousarray(p_targets, dtype=float),
            float(jump_threshold),
            _MAX_ITERATIONS,
        )

    def solve(self, q0, R_T=None, p_T=None, iterations: int = _MAX_ITERATIONS, rest=None):
        """Joints placing the frame at the orientation R_T and/or position p_T (None: free)
        within the tolerances, from q0 (7,), or None when ``iterations`` steps do not get
        there. With ``rest`` (7,), each step also moves the joints towards it in the
        Jacobian's null space, and the steps go on until that move is below 1e-4 rad: the
        joints nearest to ``rest`` (locally) that place the frame."""
        q0 = np.array(q0, dtype=float).reshape(-1)
        found, q = newton(
            q0,
            self._frame(q0),
            _NO_ROTATION if R_T is None else np.ascontiguousarray(R_T, dtype=float),
            _NO_POSITION if p_T is None else np.ascontiguousarray(p_T, dtype=float),
            R_T is not None,
            p_T is not None,
            int(iterations),
            q0 if rest is None else np.ascontiguousarray(rest, dtype=float),
            rest is not None,
        )
        return q if found else None
