"""Cartesian straight-line paths of the end effector by damped least-squares IK steps.

The hand pose is interpolated from X_WE(q_start) to the goal (position linearly, orientation by
slerp) in steps of at most ``max_step`` m and ``max_rotation_step`` rad. Each step is solved by a
few damped Newton iterations on the 6-D pose error from the previous step's joints
(``dq = J^T (J J^T + lambda^2 I)^-1 e``, J the hand's spatial-velocity Jacobian in W), which
keeps the arm on one IK branch and costs well under a millisecond per step. A step is accepted
when it converges, stays within joint limits, moves no joint more than ``jump_threshold`` rad,
and the joint-space segment to it is collision-free at ``resolution`` rad. The first step that
fails ends the path; the fraction achieved is reported.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.tree import JacobianWrtVariable

from planning.paths import densify

_MAX_ITERATIONS = 30
_POSITION_TOLERANCE = 1e-4  # m
_ANGLE_TOLERANCE = 1e-3  # rad
_DAMPING = 1e-3
_MAX_ERROR = 0.05  # m: a larger position error is cut to this in one Newton step
_MAX_TURN = 0.3  # rad: likewise for the rotation error


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


def _rotation_error(R_target: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, float]:
    """(the rotation vector of R_target R^T, in W; its angle, rad): the rotation that takes R to
    R_target."""
    M = R_target @ R.T
    angle = float(np.arccos(np.clip(0.5 * (np.trace(M) - 1.0), -1.0, 1.0)))
    if angle > 3.0:  # near a half turn the skew part vanishes: Drake's conversion
        aa = RotationMatrix(M).ToAngleAxis()
        return aa.axis() * aa.angle(), aa.angle()
    v = np.array([M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1]])
    scale = 0.5 if angle < 1e-8 else 0.5 * angle / np.sin(angle)
    return scale * v, angle


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
    """
    plant = scene.plant
    context = plant.CreateDefaultContext()
    X_WS = _pose(plant, context, frame, scene.full_q(q_start))
    distance = np.linalg.norm(X_WG.translation() - X_WS.translation())
    angle = (X_WS.rotation().inverse() @ X_WG.rotation()).ToAngleAxis().angle()
    steps = max(1, int(np.ceil(max(distance / max_step, angle / max_rotation_step))))
    R_targets, p_targets = _line(X_WS, X_WG, np.arange(1, steps + 1) / steps)
    # Every IK step first (cheap), then one batched collision check of the whole line.
    path, q, reason = [np.asarray(q_start, float)], np.asarray(q_start, float), ""
    solver = PoseNewton(
        plant, context, frame, adapter.full, scene.model.arm_indices, adapter.lower, adapter.upper
    )
    for k in range(steps):
        # Start from the last step's joint change repeated: along a straight line the next
        # joints are that close to second order, and the first check often passes.
        guess = q if len(path) < 2 else np.clip(2.0 * q - path[-2], adapter.lower, adapter.upper)
        q_next = solver.solve(guess, R_targets[k], p_targets[k])
        if q_next is None:
            reason = "no IK solution near the previous step (joint limit or singularity)"
        elif np.max(np.abs(q_next - q)) > jump_threshold:
            reason = f"joint jump above {jump_threshold} rad"
        if reason:
            break
        path.append(q_next)
        q = q_next
    path = np.asarray(path)
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


def _pose(plant, context, frame, q_full) -> RigidTransform:
    plant.SetPositions(context, q_full)
    return frame.CalcPoseInWorld(context)


class PoseNewton:
    """Damped Newton steps on the pose error of a frame (see the module docstring), on plain
    arrays: the pose as a 3x4 matrix, the error's rotation vector by the log map. Large errors
    are cut to ``_MAX_ERROR`` m / ``_MAX_TURN`` rad per step, so that far targets are approached
    gradually rather than overshot.

    Args:
        plant, context: the MultibodyPlant and a context of it (its positions are overwritten).
        frame: the frame E to place.
        full: (q) -> the plant's positions for the 7 arm joints q (the other joints fixed).
        arm: the arm joints' indices among the plant's positions.
        lower, upper: the arm's joint limits, rad.
    """

    def __init__(self, plant, context, frame, full, arm, lower, upper):
        self._plant, self._context, self._frame = plant, context, frame
        self._full, self._arm, self._lower, self._upper = full, arm, lower, upper
        self._world = plant.world_frame()

    def solve(self, q0, R_T=None, p_T=None, iterations: int = _MAX_ITERATIONS, rest=None):
        """Joints placing the frame at the orientation R_T and/or position p_T (None: free)
        within the tolerances, from q0 (7,), or None when ``iterations`` steps do not get
        there. With ``rest`` (7,), each step also moves the joints towards it in the
        Jacobian's null space, and the steps go on until that move is below 1e-4 rad: the
        joints nearest to ``rest`` (locally) that place the frame."""
        plant, context, frame = self._plant, self._context, self._frame
        rows = ([0, 1, 2] if R_T is not None else []) + ([3, 4, 5] if p_T is not None else [])
        q = np.asarray(q0, dtype=float).copy()
        for _ in range(iterations):
            plant.SetPositions(context, self._full(q))
            X = frame.CalcPoseInWorld(context).GetAsMatrix34()
            e_p, angle, e_r = np.zeros(3), 0.0, np.zeros(3)
            if p_T is not None:
                e_p = p_T - X[:, 3]
            if R_T is not None:
                e_r, angle = _rotation_error(R_T, X[:, :3])
            distance = float(np.linalg.norm(e_p))
            there = distance < _POSITION_TOLERANCE and angle < _ANGLE_TOLERANCE
            if there and rest is None:
                return q
            cut = min(1.0, _MAX_ERROR / max(distance, 1e-300), _MAX_TURN / max(angle, 1e-300))
            J = plant.CalcJacobianSpatialVelocity(
                context, JacobianWrtVariable.kQDot, frame, np.zeros(3), self._world, self._world
            )[rows][:, self._arm]
            e = cut * np.concatenate([e_r, e_p])[rows]
            inverse = J.T @ np.linalg.inv(J @ J.T + _DAMPING**2 * np.eye(len(rows)))
            dq = inverse @ e
            if rest is not None:
                drift = rest - q
                drift -= inverse @ (J @ drift)  # its part in the null space
                if there and np.linalg.norm(drift) < 1e-4:
                    return q
                dq += drift
            q = np.clip(q + dq, self._lower, self._upper)
        return None
