"""Options of ``MotionPlanner``: one dataclass per algorithm, nested in ``MotionPlannerOptions``.

The defaults here are the planner's values (there is no default options file); a user's YAML
file with any subset of them loads with ``load_planner_options(filename)``, sections nested::

    timeout: 2.0
    rrt: {step: 0.5, batch: 8}
    timing: {velocity_scaling: 0.5}

Units: rad for joints, m for lengths, s for times. "MBM" is the MotionBenchMaker Panda set
(``drake_sim.tools.plan_benchmark``). Each class's ``check()`` raises ValueError naming the bad
field ("rrt.step must be > 0, ..."). This module has no ``from __future__ import annotations``:
the YAML loader reads the field types at run time.
"""

import dataclasses as dc
import math
import numbers
from pathlib import Path

from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError
from planning.errors import ErrorCode, PlanningError


def _require(ok: bool, field: str, rule: str, value) -> None:
    """Raises ValueError "<field> must be <rule>, got <value>" unless ``ok``."""
    if not ok:
        raise ValueError(f"{field} must be {rule}, got {value!r}")


def _positive(value, field: str) -> None:
    _require(value > 0.0, field, "> 0", value)


def _finite(value, field: str, rule: str, *, zero_ok: bool) -> None:
    """Requires a finite ``value`` >= 0 (``zero_ok``) or > 0; ``rule`` says so in the message."""
    low_ok = value >= 0.0 if zero_ok else value > 0.0
    _require(low_ok and math.isfinite(value), field, rule, value)


def _seconds(value) -> bool:
    """Whether ``value`` is a wall time a request can be given: a finite number > 0 (s)."""
    number = isinstance(value, numbers.Real) and not isinstance(value, bool)
    return number and math.isfinite(value) and value > 0.0


def _fraction(value, field: str, *, zero_ok: bool) -> None:
    low_ok = value >= 0.0 if zero_ok else value > 0.0
    _require(low_ok and value <= 1.0, field, "in [0, 1]" if zero_ok else "in (0, 1]", value)


def _flag(value, field: str) -> None:
    _require(isinstance(value, bool), field, "true or false", value)


def _count(value, field: str, *, least: int) -> None:
    ok = isinstance(value, numbers.Integral) and not isinstance(value, bool) and value >= least
    _require(ok, field, f"an integer >= {least}", value)


@dc.dataclass
class RrtConnectOptions:
    """RRT-Connect (``planning.search.rrt``), ``batch`` extensions per collision query."""

    # rad, largest RRT-Connect extension (joint-space L2). Measured on all of MBM with the
    # compiled search (shortcut.iterations 40): 0.5 against 1.0, p95 24 against 37 ms, median
    # 3.2 against 3.1 ms, paths 4.91 against 5.01 rad. (Before it, the batched Python search
    # measured 1.0 with batch 16 better than 0.5 with batch 8.)
    step: float = 0.5
    goal_bias: float = 0.05  # probability of sampling the other tree's root
    # Extend the smaller tree (the start tree on a tie) rather than each in turn, as VAMP's
    # RRT-Connect does (here and in planning.search.rrt). Measured on all of MBM (compiled
    # search, in turn with the trees taking turns): 55 % fewer checks in all, p95 of the
    # compiled search 23.5 -> 10.8 ms.
    balance: bool = True
    # rad; dynamic-domain sampling (Yershova et al., ICRA 2005): after a failed extension a
    # node only grows towards targets within this distance (0: off), shrinking by 1e-4 per
    # further failure down to dynamic_domain_min. Compiled search only. Measured on all of MBM
    # with balance, against off, in two pairs of parallel runs: 4.0 (VAMP's value) p95 9.8
    # against 10.4 and 8.7 against 10.0 ms, per-problem median 7 % and 3 % lower, total time
    # the same and 6 % lower, paths 4.86 against 4.89 rad; 90 paths against 69 needed a repair
    # after the fine check (all valid). In the compiled search alone: 20 % fewer checks.
    dynamic_domain: float = 4.0
    dynamic_domain_min: float = 1.0
    batch: int = 16  # RRT-Connect extensions per collision query (1: one at a time); see step
    # s, RRT-Connect restarts with new trees after this (run times are heavy-tailed); shorter
    # restarts (1, 2.5 s) measured no better on hard MBM problems.
    restart_interval: float = 10.0

    def check(self, prefix: str = "rrt") -> None:
        """Raises ValueError naming the first field out of range."""
        _positive(self.step, f"{prefix}.step")
        _fraction(self.goal_bias, f"{prefix}.goal_bias", zero_ok=True)
        _flag(self.balance, f"{prefix}.balance")
        _finite(self.dynamic_domain, f"{prefix}.dynamic_domain", ">= 0 (0: off)", zero_ok=True)
        rule = "> 0 and finite"
        _finite(self.dynamic_domain_min, f"{prefix}.dynamic_domain_min", rule, zero_ok=False)
        _count(self.batch, f"{prefix}.batch", least=1)
        _positive(self.restart_interval, f"{prefix}.restart_interval")


@dc.dataclass
class ShortcutOptions:
    """Shortcutting of a searched path (``planning.search.shortcut``)."""

    # Random shortcut attempts after the greedy pass. Measured on all of MBM with the compiled
    # search: 40 / 50 / 60 gave median paths of 4.94 / 4.90 / 4.89 rad for median times of
    # 3.0 / 3.3 / 3.5 ms; later, with a faster kernel and both greedy passes, 30 against 50:
    # per-problem median 0.95x (benchmarks/planner_ab.py), paths 4.883 against 4.856 rad, and
    # the timed plans as long (median 2.09 against 2.10 s).
    iterations: int = 30
    time_fraction: float = 0.2  # at most this share of the remaining time goes to shortcutting

    def check(self, prefix: str = "shortcut") -> None:
        """Raises ValueError naming the first field out of range."""
        _count(self.iterations, f"{prefix}.iterations", least=0)
        _fraction(self.time_fraction, f"{prefix}.time_fraction", zero_ok=True)


@dc.dataclass
class ValidationOptions:
    """The fine collision check of every returned path, and the repair of failing segments."""

    resolution: float = 0.01  # rad between fine collision checks of every returned path
    max_repairs: int = 3  # segments re-planned when validation fails
    repair_timeout: float = 0.5  # s per segment repair; then the whole path is re-planned finely
    repair_step: float = 0.25  # rad, RRT-Connect extension when repairing (tight spots)
    # rad between collision samples of the compiled search's repair edges (the repaired path is
    # checked at ``resolution`` again, and repaired anew if it fails). Measured on the 50 MBM
    # paths whose fine check finds a sphere collision, a repair each: 0.03 took 0.42x the
    # checks of 0.01 (66.6k against 160.1k) and repaired all 50 (0.01 left two to the Python
    # pipeline), the median path no longer (5.08 against 5.10 rad).
    repair_resolution: float = 0.03
    # True: the path is valid along its whole length, not only at its samples: each sample
    # stands for the cell around it, checked with margins for how far the robot may move
    # within it (``planning.collision.checker.swept_free``). False: the samples alone, as
    # before (for comparisons; MBM Panda paths then touched obstacles between samples).
    swept: bool = True

    def check(self, prefix: str = "validation") -> None:
        """Raises ValueError naming the first field out of range."""
        field = f"{prefix}.resolution"
        _require(0.0 < self.resolution <= 0.01, field, "in (0, 0.01] rad", self.resolution)
        _count(self.max_repairs, f"{prefix}.max_repairs", least=0)
        _positive(self.repair_timeout, f"{prefix}.repair_timeout")
        _positive(self.repair_step, f"{prefix}.repair_step")
        _flag(self.swept, f"{prefix}.swept")
        field = f"{prefix}.repair_resolution"
        _finite(self.repair_resolution, field, "finite and > 0 rad", zero_ok=False)


@dc.dataclass
class PoseGoalOptions:
    """Pose goals (``MotionPlanner.plan_to_pose``): IK solutions tried in turn."""

    ik_solutions: int = 4  # distinct IK solutions tried for a pose goal

    def check(self, prefix: str = "pose") -> None:
        """Raises ValueError naming the first field out of range."""
        _count(self.ik_solutions, f"{prefix}.ik_solutions", least=1)


@dc.dataclass
class CartesianOptions:
    """Straight end-effector lines (``planning.search.cartesian``)."""

    step: float = 0.005  # m per Cartesian step
    rotation_step: float = 0.05  # rad per Cartesian step
    jump_threshold: float = 0.2  # rad, largest joint change per Cartesian step

    def check(self, prefix: str = "cartesian") -> None:
        """Raises ValueError naming the first field out of range."""
        _positive(self.step, f"{prefix}.step")
        _positive(self.rotation_step, f"{prefix}.rotation_step")
        _positive(self.jump_threshold, f"{prefix}.jump_threshold")


DEFAULT_ACCELERATION = 1.0
"""rad/s^2 (or m/s^2), a joint's acceleration limit when neither its URDF nor a joint_limits.yaml
sets one (MoveIt's time parametrisation assumes the same)."""


@dc.dataclass
class TimingOptions:
    """Joint limits the paths are timed within (``planning.timing.retime``), and their scaling."""

    # rad/s (or m/s), one per joint of the group; empty: the robot model's (its URDF's, or its
    # joint_limits.yaml's), filled in by MotionPlanner (``with_robot_limits``)
    max_velocity: list[float] = dc.field(default_factory=list)
    # rad/s^2, one per joint; empty: the robot model's (joint_limits.yaml; the Panda's: Franka's
    # datasheet), DEFAULT_ACCELERATION where it sets none
    max_acceleration: list[float] = dc.field(default_factory=list)
    velocity_scaling: float = 1.0  # (0, 1], applied to max_velocity
    acceleration_scaling: float = 1.0  # (0, 1], applied to max_acceleration

    def check(self, prefix: str = "timing") -> None:
        """Raises ValueError naming the first field out of range."""
        for name in ("max_velocity", "max_acceleration"):
            values = getattr(self, name)
            ok = all(v > 0.0 and math.isfinite(v) for v in values)
            _require(ok, f"{prefix}.{name}", "finite values > 0 (or none: the robot's)", values)
        _fraction(self.velocity_scaling, f"{prefix}.velocity_scaling", zero_ok=False)
        _fraction(self.acceleration_scaling, f"{prefix}.acceleration_scaling", zero_ok=False)

    def with_robot_limits(self, robot, prefix: str = "timing") -> "TimingOptions":
        """A copy with empty limits filled from the robot model (``RobotModel``: velocity,
        acceleration; ``DEFAULT_ACCELERATION`` where it has none).

        Raises:
            ValueError: a list given here has not one value per joint of the group, or the
                robot has no velocity limit for a joint and none is given.
        """
        n = robot.num_joints
        filled = {}
        own = {"max_velocity": robot.velocity, "max_acceleration": robot.acceleration}
        for name, limits in own.items():
            values = list(getattr(self, name))
            if not values:
                fallback = DEFAULT_ACCELERATION if name == "max_acceleration" else math.nan
                values = [float(v) if math.isfinite(v) else fallback for v in limits]
                names = robot.joint_names
                missing = [j for j, v in zip(names, values, strict=True) if math.isnan(v)]
                rule = f"given (the robot has none for {', '.join(missing)})"
                _require(not missing, f"{prefix}.{name}", rule, values)
            _require(len(values) == n, f"{prefix}.{name}", f"{n} values ({robot.group})", values)
            filled[name] = values
        return dc.replace(self, **filled)


@dc.dataclass
class KtoOptions:
    """Path smoothing with KinematicTrajectoryOptimization (``planning.search.kto``)."""

    # Smooth searched paths and keep the result when it passes the fine check and is shorter.
    # Off: measured about 1 s more per MBM problem, and only 4 of 13 results passed the 0.01 rad
    # check.
    enabled: bool = False

    def check(self, prefix: str = "kto") -> None:
        """Raises ValueError naming the first field out of range."""
        _flag(self.enabled, f"{prefix}.enabled")


@dc.dataclass
class SphereCheckOptions:
    """Sphere models of the robot (``planning.collision.spheres``) for collision queries."""

    # Answer collision queries with the spheres first (conservative: free for the spheres
    # implies free for Drake), and ask Drake's checker only where the spheres cannot decide.
    enabled: bool = True
    # m, how far spheres may bulge beyond the link meshes (smaller: a tighter cover, more spheres)
    slack: float = 0.015
    # Sphere-checked configurations of a search before Drake is asked about what the spheres
    # cannot decide (until then that counts as colliding); validation always asks Drake. The
    # compiled search (planning.search.compiled_rrt) gives up after this many, and the Python
    # pipeline then asks Drake from the start. A count, not a time, so that a seed gives the
    # same path on any machine. Measured on MBM (--limit 5, two runs each, before the compiled
    # search): 50k had the best mean (85-91 ms) and p95 (0.27 s); 10k and 25k were slower (mean
    # 107-150 ms, p95 0.56-0.63 s), and 100k missed a problem. With the compiled search the
    # Panda's MBM requests never reach 50k (50k, 200k and 1M: the same 696 paths, medians and
    # p95s), but Fetch's bookshelves need more and the Python pipeline, asking Drake, then
    # times out: on 24 of its bookshelf and cage problems 50k solved 19, 200k 21, 1M 23 (cage
    # requests the Python pipeline solved in 0.2 s after 50k now take 1.4 s in the compiled
    # search).
    drake_fallback_after: int = 1_000_000
    # rad between collision samples of the search's edges with sphere checks (the returned path
    # is validated at validation.resolution in any case).
    search_resolution: float = 0.1
    # rad; in the compiled search, samples the spheres cannot decide within this distance of the
    # start or the goal (which Drake has found free) count as free there, and Drake decides them
    # in the fine check. 0: they block, like any other. Measured on all of MBM: 0.15 solved
    # every problem (p95 23.5 ms); 0 left one to the Python search, which timed out.
    anchor_radius: float = 0.15
    # m; a second, tighter cover (this slack) decides the configurations the first cannot before
    # Drake is asked about them (0: straight to Drake). Measured on the fine checks of a third
    # of MBM's paths: 0.005 (1163 spheres) proves 55 % of those samples free, 0.002 (5105
    # spheres) 59 %, where Drake costs ~0.2 ms a configuration.
    refine_slack: float = 0.005
    # In the compiled search, the ends and fine-check samples the sphere cover cannot decide go
    # to the robot's exact convex shapes first (planning.collision.hull_kernel: a separating
    # plane with 0.1 mm to spare proves a pair apart), Drake only for what those cannot prove.
    # Measured on MBM scenes: 99 % of the samples Drake finds free are proven, at ~10 us each
    # against ~0.27 ms for Drake's check.
    hull_proofs: bool = True
    # With hull_proofs, the compiled search's edge samples that the sphere cover leaves
    # undecided for a pair of the robot's own links alone go to the exact shapes too (otherwise
    # they block the edge; compiled_rrt._proven). Arms whose links pass within the cover's slack
    # of each other at every pose (the UR5's forearm and wrist 2, about 14 mm apart) leave
    # every sample undecided, and the spheres alone never find a path: on 32 UR5 MBM problems
    # the median went from 218 to 28 ms; the Panda's MBM paths are unchanged. Since then the
    # clearance tables of such pairs (planning.collision.pair_tables) decide most of those
    # samples on the spheres (UR5 MBM median 32 -> 6 ms); the proofs take what they leave.
    search_hull_proofs: bool = True

    def check(self, prefix: str = "spheres") -> None:
        """Raises ValueError naming the first field out of range."""
        _flag(self.enabled, f"{prefix}.enabled")
        _positive(self.slack, f"{prefix}.slack")
        _count(self.drake_fallback_after, f"{prefix}.drake_fallback_after", least=0)
        _flag(self.hull_proofs, f"{prefix}.hull_proofs")
        _flag(self.search_hull_proofs, f"{prefix}.search_hull_proofs")
        _positive(self.search_resolution, f"{prefix}.search_resolution")
        _finite(self.anchor_radius, f"{prefix}.anchor_radius", ">= 0", zero_ok=True)
        _require(
            self.refine_slack == 0.0 or 0.0 < self.refine_slack < self.slack,
            f"{prefix}.refine_slack",
            f"0 (off) or in (0, slack = {self.slack})",
            self.refine_slack,
        )


@dc.dataclass
class MotionPlannerOptions:
    """Options of ``MotionPlanner``: the request budget and seed, and one section per algorithm.

    ``dc.replace(options, seed=1)`` changes a top-level field; a section's field with
    ``dc.replace(options, rrt=dc.replace(options.rrt, batch=1))``.
    """

    timeout: float = 5.0  # s of wall time per request
    seed: int = 0  # seed of np.random.default_rng, fresh for each request
    rrt: RrtConnectOptions = dc.field(default_factory=RrtConnectOptions)
    shortcut: ShortcutOptions = dc.field(default_factory=ShortcutOptions)
    validation: ValidationOptions = dc.field(default_factory=ValidationOptions)
    pose: PoseGoalOptions = dc.field(default_factory=PoseGoalOptions)
    cartesian: CartesianOptions = dc.field(default_factory=CartesianOptions)
    timing: TimingOptions = dc.field(default_factory=TimingOptions)
    kto: KtoOptions = dc.field(default_factory=KtoOptions)
    spheres: SphereCheckOptions = dc.field(default_factory=SphereCheckOptions)

    def check(self) -> None:
        """Raises ValueError naming the first field out of range, sections included."""
        _require(_seconds(self.timeout), "timeout", "a finite number of seconds > 0", self.timeout)
        _count(self.seed, "seed", least=0)
        for field in dc.fields(self):
            section = getattr(self, field.name)
            if dc.is_dataclass(section):
                section.check(field.name)


def request_timeout(timeout, default) -> float:
    """The wall time a planning request may take, s: its ``timeout``, or ``default`` (the
    options' ``timeout``) when that is None. Called at a request's start, before any search.

    Raises:
        PlanningError: INVALID_MOTION_PLAN (an invalid request) when the value is not a finite
            number of seconds > 0: NaN, infinite, zero, negative, a bool or a string.
    """
    value, name = (default, "options.timeout") if timeout is None else (timeout, "timeout")
    if not _seconds(value):
        raise PlanningError(
            ErrorCode.INVALID_MOTION_PLAN,
            f"invalid request: {name} must be a finite number of seconds > 0, got {value!r}",
        )
    return float(value)


def load_planner_options(filename: Path | str) -> MotionPlannerOptions:
    """Loads options from a YAML file; fields it leaves out keep their defaults.

    Raises:
        ConfigError: the file is missing or malformed, has an unknown key, a value of the wrong
            type or one out of range (``MotionPlannerOptions.check``), naming the file and key.
    """
    options = load_typed(MotionPlannerOptions, filename=filename)
    try:
        options.check()
    except ValueError as e:
        raise ConfigError(f"{filename}: {e}") from None
    return options
