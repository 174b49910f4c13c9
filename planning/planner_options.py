"""Options of ``MotionPlanner`` and their YAML file (``config/planner.yaml``).

Units: rad for joints, m for lengths, s for times. This module has no ``from __future__ import
annotations``: the YAML loader reads the field types at run time.
"""

import dataclasses as dc
from pathlib import Path

from pydrake.common.yaml import yaml_load_typed

from drake_sim.base.resources import config_dir


@dc.dataclass
class MotionPlannerOptions:
    """Options of ``MotionPlanner`` (values in ``config/planner.yaml``)."""

    timeout: float = 5.0  # s of wall time per request
    seed: int = 0  # seed of np.random.default_rng, fresh for each request
    rrt_step: float = 1.0  # rad, largest RRT-Connect extension (joint-space L2)
    goal_bias: float = 0.05  # probability of sampling the other tree's root
    rrt_batch: int = 16  # RRT-Connect extensions per collision query (1: one at a time)
    rrt_restart_interval: float = 10.0  # s, RRT-Connect restarts with new trees after this
    shortcut_iterations: int = 20  # random shortcut attempts after the greedy pass
    shortcut_time_fraction: float = 0.2  # share of the remaining time shortcutting may use
    validation_resolution: float = 0.01  # rad between fine checks of every returned path
    max_repairs: int = 3  # segments re-planned with fine edge checks when validation fails
    repair_timeout: float = 0.5  # s per segment repair attempt; then the whole path is re-planned
    repair_step: float = 0.25  # rad, RRT-Connect extension when repairing (tight spots)
    ik_solutions: int = 4  # distinct IK solutions tried for a pose goal
    cartesian_step: float = 0.005  # m per Cartesian step
    cartesian_rotation_step: float = 0.05  # rad per Cartesian step
    cartesian_jump_threshold: float = 0.2  # rad, largest joint change per Cartesian step
    max_velocity: list[float] = dc.field(
        default_factory=lambda: [2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61]
    )  # rad/s
    max_acceleration: list[float] = dc.field(
        default_factory=lambda: [15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0]
    )  # rad/s^2
    velocity_scaling: float = 1.0  # (0, 1]
    acceleration_scaling: float = 1.0  # (0, 1]
    # Smooth searched paths with KinematicTrajectoryOptimization (planning.search.kto) and keep the
    # result when it passes the fine check and is shorter. Off: measured about 1 s more per MBM
    # problem, and only 4 of 13 results passed the 0.01 rad check.
    refine_with_kto: bool = False
    # Answer collision queries with sphere models of the robot first (planning.collision.spheres),
    # and ask Drake's checker only where the spheres cannot decide.
    sphere_checks: bool = True
    sphere_slack: float = 0.015  # m, how far spheres may bulge beyond the link meshes
    # Sphere-checked configurations of a search before Drake is asked about what the spheres
    # cannot decide (until then that counts as colliding); validation always asks Drake. A
    # count, not a time, so that a seed gives the same path on any machine.
    drake_fallback_after: int = 50_000
    # rad between collision samples of the search's edges with sphere checks (the returned path
    # is validated at validation_resolution in any case).
    search_resolution: float = 0.1


def load_planner_options(filename: Path | str | None = None) -> MotionPlannerOptions:
    """Loads options from YAML (``config/planner.yaml`` when None); unknown keys are errors."""
    if filename is None:
        filename = config_dir() / "planner.yaml"
    return yaml_load_typed(schema=MotionPlannerOptions, filename=str(filename))


def check_options(options: MotionPlannerOptions) -> None:
    """Raises ValueError for options no planner can use."""
    positive = (
        "timeout",
        "rrt_step",
        "rrt_restart_interval",
        "validation_resolution",
        "cartesian_step",
        "sphere_slack",
        "search_resolution",
        "repair_timeout",
        "repair_step",
    )
    bad = [name for name in positive if getattr(options, name) <= 0.0]
    if not (0.0 < options.velocity_scaling <= 1.0 and 0.0 < options.acceleration_scaling <= 1.0):
        bad.append("velocity_scaling/acceleration_scaling (must be in (0, 1])")
    if len(options.max_velocity) != 7 or len(options.max_acceleration) != 7:
        bad.append("max_velocity/max_acceleration (7 values each)")
    if options.rrt_batch < 1 or options.drake_fallback_after < 0:
        bad.append("rrt_batch (at least 1)/drake_fallback_after (not negative)")
    if options.validation_resolution > 0.01:
        bad.append("validation_resolution (at most 0.01 rad)")
    if bad:
        raise ValueError(f"bad MotionPlannerOptions: {', '.join(bad)}")
