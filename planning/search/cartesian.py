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
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.tree import JacobianWrtVariable

from planning.paths import densify

_MAX_ITERATIONS = 30
_POSITION_TOLERANCE = 1e-4  # m
_ANGLE_TOLERANCE = 1e-3  # rad
_DAMPING = 1e-3


@dataclass
class CartesianPath:
    """Waypoints (N, 7) in rad achieved along the line, the fraction in [0, 1], and why it
    stopped ("" when complete)."""

    waypoints: np.ndarray
    fraction: float
    reason: str


def interpolate_pose(X_a: RigidTransform, X_b: RigidTransform, s: float) -> RigidTransform:
    """Pose a fraction s of the way from X_a to X_b (linear position, slerp orientation)."""
    q_a = X_a.rotation().ToQuaternion()
    q_b = X_b.rotation().ToQuaternion()
    quat = q_a.slerp(s, q_b)
    p = (1.0 - s) * X_a.translation() + s * X_b.translation()
    return RigidTransform(RotationMatrix(Quaternion(quat.wxyz() / np.linalg.norm(quat.wxyz()))), p)


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
    # Every IK step first (cheap), then one batched collision check of the whole line.
    path, q, reason = [np.asarray(q_start, float)], np.asarray(q_start, float), ""
    for k in range(1, steps + 1):
        target = interpolate_pose(X_WS, X_WG, k / steps)
        q_next = _solve_step(scene, adapter, plant, context, frame, q, target)
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


def _solve_step(scene, adapter, plant, context, frame, q0, X_WT) -> np.ndarray | None:
    arm = scene.model.arm_indices
    q = q0.copy()
    for _ in range(_MAX_ITERATIONS):
        full = adapter.full(q)
        X_WE = _pose(plant, context, frame, full)
        e_p = X_WT.translation() - X_WE.translation()
        aa = (X_WT.rotation() @ X_WE.rotation().inverse()).ToAngleAxis()
        e_r = aa.axis() * aa.angle()
        if np.linalg.norm(e_p) < _POSITION_TOLERANCE and aa.angle() < _ANGLE_TOLERANCE:
            return q
        J = plant.CalcJacobianSpatialVelocity(
            context,
            JacobianWrtVariable.kQDot,
            frame,
            np.zeros(3),
            plant.world_frame(),
            plant.world_frame(),
        )[:, arm]
        e = np.concatenate([e_r, e_p])
        dq = J.T @ np.linalg.solve(J @ J.T + _DAMPING**2 * np.eye(6), e)
        q = np.clip(q + dq, adapter.lower, adapter.upper)
    return None
