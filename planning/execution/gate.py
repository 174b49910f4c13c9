"""The one check before motion: a plan against the robot and the scene as they are now.

Everything that moves the arm along a plan goes through ``check_before_motion``: it is called by
``MotionPlanningInterface.execute_async``, so by ``execute``, the ``move_*`` calls, a plan loaded
from a file and executed in a running station, and every arm step of
``planning.task.pick_place``. The checks, in this order; the first violation is raised, and
nothing is commanded:

1. the plan is a ``Plan`` for the robot's seven arm joints, its stored values (waypoints,
   limits, fingers, duration) finite;
2. its stored limits within the robot's own (``limits``: the planner's ``TimingOptions``, the
   Panda's datasheet limits): a plan may be slower than the robot, never faster;
3. every waypoint within the robot's position limits (the scene's plant);
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
from planning.model.layout import NUM_ARM_JOINTS, NUM_FINGERS
from planning.model.panda import ARM_JOINTS
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
        q_measured: (7,) the measured arm joints, rad.
        fingers_measured: (2,) the measured finger positions, m.
        limits: the robot's own limits: ``max_velocity`` (7,) rad/s and ``max_acceleration``
            (7,) rad/s^2 (e.g. ``TimingOptions``, unscaled).
        start_tolerance: rad, the largest joint gap between the trajectory's start and
            ``q_measured``.
        resolution: rad, joint-space step of the collision check.
        dt: s, time step at which the trajectory is sampled.

    Raises:
        PlanningError: INVALID_MOTION_PLAN naming the first violation; INVALID_START when the
            trajectory starts more than ``start_tolerance`` from the measured joints (or the
            measured state is not finite).
    """
    _check_values(plan)
    robot_v = np.asarray(limits.max_velocity, dtype=float)
    robot_a = np.asarray(limits.max_acceleration, dtype=float)
    _check_stored_limits(plan, robot_v, robot_a)
    lower, upper = _position_limits(scene)
    for k, q in enumerate(plan.waypoints):
        _check_positions(q, lower, upper, f"waypoint {k}")
    _check_start(plan, q_measured, fingers_measured, start_tolerance)
    _check_trajectory(plan, (lower, upper), robot_v, robot_a, dt)
    fingers = np.asarray(fingers_measured, dtype=float)
    try:
        plan.validate(scene, resolution, finger_positions=fingers)
    except PlanningError as e:
        where = f"with the fingers as measured ({fingers[0]:.4f}, {fingers[1]:.4f} m)"
        raise _invalid(f"{where}, {e.message}") from None


def _invalid(message: str) -> PlanningError:
    return PlanningError(ErrorCode.INVALID_MOTION_PLAN, message)


def _check_values(plan) -> None:
    if not isinstance(plan, Plan):
        raise _invalid(f"not a Plan: {type(plan).__name__}")
    joints = plan.robot.get("joints") if isinstance(plan.robot, dict) else None
    if not isinstance(joints, list | tuple) or list(joints) != list(ARM_JOINTS):
        raise _invalid(f"the plan is for the joints {joints}, the robot's are {list(ARM_JOINTS)}")
    sizes = {
        "waypoints": (len(plan.waypoints), NUM_ARM_JOINTS),
        "max_velocity": (NUM_ARM_JOINTS,),
        "max_acceleration": (NUM_ARM_JOINTS,),
        "finger_positions": (NUM_FINGERS,),
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


def _check_stored_limits(plan, robot_v: np.ndarray, robot_a: np.ndarray) -> None:
    for name, stored, robot, unit in (
        ("max_velocity", plan.max_velocity, robot_v, "rad/s"),
        ("max_acceleration", plan.max_acceleration, robot_a, "rad/s^2"),
    ):
        for j in range(NUM_ARM_JOINTS):
            what = f"{ARM_JOINTS[j]}: the plan's {name} {stored[j]:.4g} {unit}"
            if stored[j] > robot[j] * (1.0 + RATE_TOLERANCE):
                raise _invalid(f"{what} is above the robot's limit {robot[j]:.4g} {unit}")
            if stored[j] <= 0.0:
                raise _invalid(f"{what} is not > 0")


def _position_limits(scene) -> tuple[np.ndarray, np.ndarray]:
    """The robot's arm joint limits (lower, upper), rad, from the scene's plant."""
    arm = scene.model.arm_indices
    return scene.plant.GetPositionLowerLimits()[arm], scene.plant.GetPositionUpperLimits()[arm]


def _check_positions(q: np.ndarray, lower, upper, where: str) -> None:
    outside = (q < lower - POSITION_TOLERANCE) | (q > upper + POSITION_TOLERANCE)
    if outside.any():
        j = int(np.argmax(outside))
        raise _invalid(
            f"{where}: {ARM_JOINTS[j]} at {q[j]:.4f} rad is outside its limits "
            f"[{lower[j]:.4f}, {upper[j]:.4f}] rad"
        )


def _check_start(plan: Plan, q_measured, fingers_measured, tolerance: float) -> None:
    q = np.asarray(q_measured, dtype=float)
    measured = np.concatenate([q.reshape(-1), np.asarray(fingers_measured, dtype=float)])
    if measured.size != NUM_ARM_JOINTS + NUM_FINGERS or not np.all(np.isfinite(measured)):
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
            f"({ARM_JOINTS[j]}: plan {start[j]:.4f} rad, measured {q[j]:.4f} rad; "
            f"tolerance {tolerance} rad)",
        )


def _check_trajectory(plan: Plan, position_limits, robot_v, robot_a, dt: float) -> None:
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
        raise _invalid(f"at t = {t:.3f} s the {name} of {ARM_JOINTS[j]} is {values[k][j]}")
    if limit is None:
        _check_positions(q[k], lower, upper, f"at t = {t:.3f} s")
    unit = {"velocity": "rad/s", "acceleration": "rad/s^2"}[name]
    j = int(np.argmax(np.abs(values[k]) / limit))
    raise _invalid(
        f"at t = {t:.3f} s {ARM_JOINTS[j]} {name} {values[k][j]:.4g} {unit} is above the "
        f"robot's limit {limit[j]:.4g} {unit}"
    )
