"""The one check before motion: a plan against the robot and the scene as they are now.

Everything that moves the arm along a plan goes through ``check_before_motion``: it is called by
``MotionPlanningInterface.execute_async``, so by ``execute``, the ``move_*`` calls, a plan loaded
from a file and executed in a running station, and every arm step of
``planning.task.pick_place``. The checks, in this order; the first violation is raised, and
nothing is commanded:

1. the plan is a ``Plan`` for the scene's robot and planning group (``Plan.check_robot``), its
   stored values (waypoints, limits, fingers, duration) finite and of the robot's sizes;
2. its stored limits within the robot's own (``limits``: the planner's ``TimingOptions``, the
   robot model's limits): a plan may be slower than the robot, never faster;
3. every waypoint within the group's position limits, the fingers within theirs (the scene's
   robot model and plant);
4. the trajectory's start at the measured joints, within ``start_tolerance``;
5. the trajectory itself, sampled every ``dt`` and at its waypoint times: finite, within the
   position limits, and within the robot's velocity and acceleration limits (so a plan whose
   trajectory does not follow its stored limits is caught too);
6. collision-free at ``resolution`` (``Plan.validate``) with the fingers where they are measured
   and the attached objects as the scene holds them now (not as the plan was made).

Jerk is not checked: plans carry no jerk limit, and their accelerations are piecewise constant
(rest to rest) or piecewise smooth (TOPP-RA), switching at a single instant.

A violation raises ``PlanningError(INVALID_MOTION_PLAN)`` naming it (joint, time, value, limit),
except a start away from the robot: ``INVALID_START`` (the plan may be fine; the robot is
elsewhere).
"""

from __future__ import annotations

import numpy as np

from planning.errors import ErrorCode, PlanningError
from planning.plan import Plan

POSITION_TOLERANCE = 1e-6
"""rad, how far beyond a position limit a value may be (rounding)."""
RATE_TOLERANCE = 1e-6
"""Relative: a sampled velocity or acceleration may exceed the robot's limit by this share."""
MAX_SAMPLES = 200_000
"""The most trajectory samples checked; a longer plan is sampled more coarsely than ``dt``."""


def check_before_motion(
    plan,
    scene,
    q_measured,
    fingers_measured,
    limits,
    *,
    start_tolerance: float,
    resolution: float = 0.01,
    dt: float = 1e-3,
) -> None:
    """Checks ``plan`` against the robot and the scene as they are now (see the module).

    Args:
        plan: the ``Plan`` about to be executed.
        scene: the ``PlanningScene`` now (objects, attached objects, the robot's plant).
        q_measured: (n,) the measured joints of the group, rad.
        fingers_measured: the measured finger positions (the Panda's: 2, m).
        limits: the robot's own limits: ``max_velocity`` (n,) rad/s and ``max_acceleration``
            (n,) rad/s^2 (e.g. the planner's ``TimingOptions``, unscaled).
        start_tolerance: rad, the largest joint gap between the trajectory's start and
            ``q_measured``.
        resolution: rad, joint-space step of the collision check.
        dt: s, time step at which the trajectory is sampled.

    Raises:
        PlanningError: INVALID_MOTION_PLAN naming the first violation; INVALID_START when the
            trajectory starts more than ``start_tolerance`` from the measured joints (or the
            measured state is not finite).
    """
    names = _check_values(plan, scene)
    robot_v = np.asarray(limits.max_velocity, dtype=float)
    robot_a = np.asarray(limits.max_acceleration, dtype=float)
    _check_stored_limits(plan, robot_v, robot_a, names)
    lower, upper = scene.lower, scene.upper
    for k, q in enumerate(plan.waypoints):
        _check_positions(q, lower, upper, f"waypoint {k}", names)
    _check_fingers(plan, scene)
    _check_start(plan, q_measured, fingers_measured, start_tolerance, names)
    _check_trajectory(plan, (lower, upper), robot_v, robot_a, dt, names)
    fingers = np.asarray(fingers_measured, dtype=float)
    try:
        plan.validate(scene, resolution, finger_positions=fingers)
    except PlanningError as e:
        shown = ", ".join(f"{f:.4f}" for f in fingers)
        raise _invalid(f"with the fingers as measured ({shown}), {e.message}") from None


def _invalid(message: str) -> PlanningError:
    return PlanningError(ErrorCode.INVALID_MOTION_PLAN, message)


def _check_values(plan, scene) -> list[str]:
    """Checks the plan is for the scene's robot, of its sizes and finite; returns the group's
    joint names."""
    if not isinstance(plan, Plan):
        raise _invalid(f"not a Plan: {type(plan).__name__}")
    plan.check_robot(scene)
    names = scene.model.joint_names
    n, fingers = len(names), int(scene.model.finger_mask.sum())
    sizes = {
        "waypoints": (len(plan.waypoints), n),
        "max_velocity": (n,),
        "max_acceleration": (n,),
        "finger_positions": (fingers,),
    }
    for name, shape in sizes.items():
        value = np.asarray(getattr(plan, name), dtype=float)
        if value.shape != shape:
            raise _invalid(f"the plan's {name} has shape {value.shape}, not {shape}")
        bad = np.argwhere(~np.isfinite(value))
        if len(bad):
            index = "][".join(str(i) for i in bad[0])
            raise _invalid(f"the plan's {name}[{index}] is {value[tuple(bad[0])]}, not finite")
    if not np.isfinite(plan.duration) or plan.duration < 0.0:
        raise _invalid(f"the plan's duration is {plan.duration} s, not a finite time")
    return names


def _check_fingers(plan, scene) -> None:
    """The plan's finger positions within the finger joints' limits (the scene's plant)."""
    model, plant = scene.model, scene.plant
    indices = model.finger_indices
    lower = plant.GetPositionLowerLimits()[indices]
    upper = plant.GetPositionUpperLimits()[indices]
    for k, value in enumerate(plan.finger_positions):
        if not lower[k] - POSITION_TOLERANCE <= value <= upper[k] + POSITION_TOLERANCE:
            raise _invalid(
                f"the plan's finger_positions[{k}] {value:.4f} is outside the finger's limits "
                f"[{lower[k]:.4f}, {upper[k]:.4f}]"
            )


def _check_stored_limits(plan, robot_v: np.ndarray, robot_a: np.ndarray, names) -> None:
    for name, stored, robot, unit in (
        ("max_velocity", plan.max_velocity, robot_v, "rad/s"),
        ("max_acceleration", plan.max_acceleration, robot_a, "rad/s^2"),
    ):
        for j in range(len(names)):
            what = f"{names[j]}: the plan's {name} {stored[j]:.4g} {unit}"
            if stored[j] > robot[j] * (1.0 + RATE_TOLERANCE):
                raise _invalid(f"{what} is above the robot's limit {robot[j]:.4g} {unit}")
            if stored[j] <= 0.0:
                raise _invalid(f"{what} is not > 0")


def _check_positions(q: np.ndarray, lower, upper, where: str, names) -> None:
    outside = (q < lower - POSITION_TOLERANCE) | (q > upper + POSITION_TOLERANCE)
    if outside.any():
        j = int(np.argmax(outside))
        raise _invalid(
            f"{where}: {names[j]} at {q[j]:.4f} rad is outside its limits "
            f"[{lower[j]:.4f}, {upper[j]:.4f}] rad"
        )


def _check_start(plan: Plan, q_measured, fingers_measured, tolerance: float, names) -> None:
    q = np.asarray(q_measured, dtype=float)
    fingers = np.asarray(fingers_measured, dtype=float).reshape(-1)
    measured = np.concatenate([q.reshape(-1), fingers])
    size = len(names) + len(plan.finger_positions)
    if measured.size != size or not np.all(np.isfinite(measured)):
        raise PlanningError(
            ErrorCode.INVALID_START, f"the measured state is not finite: {measured.tolist()}"
        )
    start = plan.sample(0.0)[0]
    gaps = np.abs(start - q)
    j = int(np.argmax(gaps))
    if gaps[j] > tolerance:
        raise PlanningError(
            ErrorCode.INVALID_START,
            f"the plan starts {gaps[j]:.3f} rad from the robot's current joints "
            f"({names[j]}: plan {start[j]:.4f} rad, measured {q[j]:.4f} rad; "
            f"tolerance {tolerance} rad)",
        )


def _check_trajectory(plan: Plan, position_limits, robot_v, robot_a, dt: float, names) -> None:
    """Samples the trajectory and raises at the first sample (in time) out of the limits."""
    step = max(dt, plan.duration / MAX_SAMPLES)
    ts = np.unique(np.concatenate([np.arange(0.0, plan.duration, step), plan.times]))
    samples = [plan.sample(t) for t in ts]
    q, v, a = (np.array([s[i] for s in samples]) for i in range(3))
    lower, upper = position_limits
    tol = 1.0 + RATE_TOLERANCE
    checks = (
        ("position", q, None),
        ("velocity", v, robot_v),
        ("acceleration", a, robot_a),
    )
    bad_rows = []
    for _, values, limit in checks:
        if limit is None:
            bad = (q < lower - POSITION_TOLERANCE) | (q > upper + POSITION_TOLERANCE)
        else:
            bad = np.abs(values) > limit * tol
        bad_rows.append((~np.isfinite(values) | bad).any(axis=1))
    first = [int(np.argmax(rows)) if rows.any() else len(ts) for rows in bad_rows]
    k = min(first)
    if k == len(ts):
        return
    kind = first.index(k)
    name, values, limit = checks[kind]
    t = ts[k]
    if not np.all(np.isfinite(values[k])):
        j = int(np.argmax(~np.isfinite(values[k])))
        raise _invalid(f"at t = {t:.3f} s the {name} of {names[j]} is {values[k][j]}")
    if limit is None:
        _check_positions(q[k], lower, upper, f"at t = {t:.3f} s", names)
    unit = {"velocity": "rad/s", "acceleration": "rad/s^2"}[name]
    j = int(np.argmax(np.abs(values[k]) / limit))
    raise _invalid(
        f"at t = {t:.3f} s {names[j]} {name} {values[k][j]:.4g} {unit} is above the "
        f"robot's limit {limit[j]:.4g} {unit}"
    )
