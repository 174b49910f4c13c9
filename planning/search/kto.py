"""Optional smoothing of a joint path with Drake's KinematicTrajectoryOptimization (KTO).

The path found by RRT-Connect seeds a B-spline (control points sampled along it by arc length);
KTO then minimises duration and path length under joint position and velocity limits, fixed
ends, and a ``MinimumDistanceLowerBoundConstraint`` built on the scene's collision checker (so
objects added at run time count) at ``collision_samples`` values of the path parameter. The
result is sampled into a dense piecewise-linear path so that the caller re-checks it at the fine
resolution like any other path; when the solver fails, None is returned and the caller keeps
the seed. Measured on the MBM problems (see the report of issue 5), this is slower than the
shortcut pass and not the default.
"""

from __future__ import annotations

import numpy as np
from pydrake.multibody.inverse_kinematics import MinimumDistanceLowerBoundConstraint
from pydrake.planning import KinematicTrajectoryOptimization
from pydrake.solvers import Solve
from pydrake.trajectories import BsplineTrajectory

from planning.collision.checker import first_invalid_segment
from planning.paths import path_length


def kto_shorter(scene, path, how: str, max_velocity, adapter, validation) -> tuple[np.ndarray, str]:
    """``kto_refine``'s path in place of ``path`` when it is shorter and free along its whole
    length on ``adapter`` (``validation``'s resolution and swept check), with "+kto" added to
    ``how``; else ``path`` and ``how`` as they were."""
    dense = kto_refine(scene, path, max_velocity=np.asarray(max_velocity))
    if dense is None or path_length(dense) >= path_length(path):
        return path, how
    if first_invalid_segment(adapter, dense, validation.resolution, validation.swept) is not None:
        return path, how
    return dense, how + "+kto"


def kto_refine(
    scene,
    path: np.ndarray,
    *,
    max_velocity: np.ndarray,
    control_points: int = 12,
    collision_samples: int = 50,
    minimum_distance: float = 0.001,
    sample_step: float = 0.005,
) -> np.ndarray | None:
    """Smooths a collision-free path (N, 7) with KTO; returns a dense path or None.

    Args:
        scene: the planning scene (its checker's geometry is the constraint's).
        path: (N, 7) arm waypoints, rad.
        max_velocity: (7,) rad/s.
        control_points: B-spline control points.
        collision_samples: path parameters at which the distance constraint is imposed.
        minimum_distance: m, lower bound on signed distances.
        sample_step: rad, joint-space spacing of the returned samples (at most).
    """
    plant = scene.plant
    n = plant.num_positions()
    arm = scene.model.arm_indices
    full = np.array([scene.full_q(q) for q in path])
    trajopt = KinematicTrajectoryOptimization(n, control_points, 4, 1.0)
    prog = trajopt.get_mutable_prog()
    trajopt.AddDurationCost(1.0)
    trajopt.AddPathLengthCost(1.0)
    lower, upper = plant.GetPositionLowerLimits().copy(), plant.GetPositionUpperLimits().copy()
    fingers = scene.model.finger_indices
    lower[fingers] = upper[fingers] = full[0][fingers]
    trajopt.AddPositionBounds(lower, upper)
    v = np.full(n, 1e-6)
    v[arm] = max_velocity
    trajopt.AddVelocityBounds(-v, v)
    trajopt.AddDurationConstraint(0.1, 20.0)
    trajopt.AddPathPositionConstraint(full[0], full[0], 0.0)
    trajopt.AddPathPositionConstraint(full[-1], full[-1], 1.0)
    context = scene.checker.MakeStandaloneModelContext()
    constraint = MinimumDistanceLowerBoundConstraint(
        scene.checker, minimum_distance, context, None, 0.05
    )
    for s in np.linspace(0.0, 1.0, collision_samples):
        trajopt.AddPathPositionConstraint(constraint, s)
    # Seed: control points along the path by arc length.
    cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(full, axis=0), axis=1))])
    targets = np.linspace(0.0, cum[-1], control_points)
    seed = np.array([np.interp(targets, cum, full[:, j]) for j in range(n)])
    trajopt.SetInitialGuess(BsplineTrajectory(trajopt.basis(), list(seed.T.reshape(-1, n, 1))))
    result = Solve(prog)
    if not result.is_success():
        return None
    traj = trajopt.ReconstructTrajectory(result)
    # Sample densely enough that consecutive samples are at most sample_step apart.
    ts = np.linspace(traj.start_time(), traj.end_time(), 200)
    qs = np.array([traj.value(t).ravel() for t in ts])
    length = np.linalg.norm(np.diff(qs, axis=0), axis=1).sum()
    count = max(2, int(np.ceil(length / sample_step)) * 2)
    ts = np.linspace(traj.start_time(), traj.end_time(), count)
    return np.array([traj.value(t).ravel()[arm] for t in ts])
