"""A planned motion: a timed joint trajectory that remembers the scene and robot it was made for.

File format (JSON, one object; ``Plan.save`` / ``Plan.load``)::

    {
      "format": "drake_sim.plan", "version": 3,
      "robot": {"name": "panda", "group": "arm", "joints": ["panda_joint1", ...],
                "fingers": ["panda_finger_joint1", "panda_finger_joint2"]},
      "waypoints": [[q1..qn], ...],            # rad (m), the group's joints, the checked path
      "max_velocity": [n values],              # rad/s, limits after scaling
      "max_acceleration": [n values],          # rad/s^2, limits after scaling
      "velocity_scaling": 1.0, "acceleration_scaling": 1.0,
      "finger_positions": [f1, f2],            # robot.fingers (the joints below the attach
                                               # link), held during the motion (the Panda's: m)
      "timing": {"method": "toppra", "max_corner_angle": 1.0,   # rad
                 "path_tolerance": 0.002, "margin": 0.01},      # rad, fraction
      "scene": {"world": [object, ...], "attached": [object, ...]},
      "info": {...}                            # free-form: planner, planning time, ...
    }

where an object is ``{"name", "shape", "size", "position", "orientation": [x, y, z, w]}`` as in
``scene_objects`` (world objects: pose X_WO; attached ones: X_AO in the hand's attachment frame).
``timing`` holds ``planning.timing.retime.RetimeOptions``. Version 1 files have no ``timing``: they
load with ``method: rest_to_rest`` (a stop at every waypoint), the timing they were saved with;
version 1 and 2 files have no ``robot.group`` (they are the Panda's arm). A plan records its
robot and group and is refused by a scene of another robot or group (``Plan.check_robot``).
Times are not stored: they follow from the waypoints, limits and timing options
(``planning.timing.retime``), so a loaded plan samples exactly as the saved one. Floats are written
with ``repr`` precision, so a plan loads back equal.

``Plan.load`` and ``Plan.from_dict`` check every field against the schema of
``planning.io.plan_files`` first: anything missing, unknown, non-finite, of the wrong type or
length, out of range, or a file that is not UTF-8 JSON, raises
``PlanningError(ErrorCode.INVALID_MOTION_PLAN)`` naming the file and the field
(``waypoints[3][2]``). A loaded plan is checked against the robot itself before it moves it
(``planning.execution.gate``).
"""

from __future__ import annotations

import dataclasses as dc
import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drake_sim.base.files import write_atomic
from planning.collision.checker import CheckerAdapter, first_invalid_segment
from planning.errors import ErrorCode, PlanningError
from planning.io.plan_files import FORMAT, VERSION, check_plan_data, invalid, read_plan_json
from planning.model.layout import FINGER_OPEN, NUM_FINGERS
from planning.model.panda import ARM_JOINTS, FINGER_JOINTS
from planning.scene_objects import describe_scene
from planning.timing.retime import RetimeOptions, Timing

PANDA_ARM = {"name": "panda", "group": "arm", "fingers": list(FINGER_JOINTS)}
"""The robot of a plan made without one (the Panda's arm, as every version 1 and 2 file)."""
_UNTIMEABLE = "the waypoints cannot be timed within the limits"


@dataclass
class Plan:
    """A timed trajectory through joint waypoints (see ``planning.timing.retime``).

    The trajectory starts and ends at rest exactly at the first and last waypoints, stops at
    sharp corners of the path, and elsewhere stays within ``timing.path_tolerance`` (rad) of the
    straight segments between the waypoints; no joint exceeds ``max_velocity`` or
    ``max_acceleration``.

    Attributes:
        waypoints: (N, n) the group's joints (rad or m); the straight-line interpolation is the
            checked path.
        max_velocity: (n,) joint speed limits used, rad/s (already scaled).
        max_acceleration: (n,) joint acceleration limits used, rad/s^2 (already scaled).
        velocity_scaling, acceleration_scaling: the factors applied to the robot's limits.
        finger_positions: the fingers (joints below the attach link) during the motion.
        scene: ``describe_scene`` of the scene it was planned in.
        robot: the robot's name, its planning group and the group's joint names (n).
        timing: how the path is timed (``planning.timing.retime.RetimeOptions``).
        info: free-form facts (planner, planning time, path length, ...).
    """

    waypoints: np.ndarray
    max_velocity: np.ndarray
    max_acceleration: np.ndarray
    velocity_scaling: float = 1.0
    acceleration_scaling: float = 1.0
    finger_positions: np.ndarray = field(default_factory=lambda: np.full(NUM_FINGERS, FINGER_OPEN))
    scene: dict = field(default_factory=lambda: {"world": [], "attached": []})
    robot: dict = field(default_factory=lambda: dict(PANDA_ARM, joints=list(ARM_JOINTS)))
    info: dict = field(default_factory=dict)
    timing: RetimeOptions = field(default_factory=RetimeOptions)

    def __post_init__(self):
        self.waypoints = np.atleast_2d(np.asarray(self.waypoints, dtype=float))
        self.max_velocity = np.asarray(self.max_velocity, dtype=float)
        self.max_acceleration = np.asarray(self.max_acceleration, dtype=float)
        self.finger_positions = np.asarray(self.finger_positions, dtype=float).reshape(-1)
        self.robot = {"group": "", "fingers": PANDA_ARM["fingers"], **self.robot}
        n = len(self.robot["joints"])
        if self.waypoints.shape[1] != n or len(self.waypoints) < 1:
            raise ValueError(f"waypoints must be (N, {n}), got {self.waypoints.shape}")
        sizes = {"max_velocity": n, "max_acceleration": n}
        sizes.update(finger_positions=len(self.robot["fingers"]), waypoints=self.waypoints.size)
        for name, size in sizes.items():
            value = getattr(self, name)
            if value.size != size or not np.all(np.isfinite(value)):
                shown = value.tolist() if value.size <= 2 * n else value.shape
                raise ValueError(f"{name} must be {size} finite values, got {shown}")
        if np.any(self.max_velocity <= 0) or np.any(self.max_acceleration <= 0):
            raise ValueError("velocity and acceleration limits must be positive")
        if isinstance(self.timing, dict):
            self.timing = RetimeOptions(**self.timing)
        try:
            self._timing = Timing(
                self.waypoints, self.max_velocity, self.max_acceleration, self.timing
            )
        except (RuntimeError, SystemExit) as e:  # Drake's trajectory checks (SystemExit too)
            first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
            raise ValueError(f"{_UNTIMEABLE}: {first}") from None

    # ------------------------------------------------------------------------- inspect ----
    @property
    def duration(self) -> float:
        """Total time, s."""
        return self._timing.duration

    @property
    def times(self) -> np.ndarray:
        """Time at which the trajectory passes each waypoint, s."""
        return self._timing.times.copy()

    @property
    def stop_times(self) -> np.ndarray:
        """Times at which the robot is at rest (start, sharp corners, end), s."""
        return self._timing.times[self._timing.stops]

    @property
    def path_length(self) -> float:
        """Joint-space L2 length, rad."""
        return float(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1).sum())

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Returns (q rad, v rad/s, a rad/s^2) of the group's joints at time t (clamped)."""
        return self._timing.sample(float(t))

    def sample_many(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Returns (times (M,), q (M, n)) every dt seconds, the end included."""
        ts = np.append(np.arange(0.0, self.duration, dt), self.duration)
        return ts, np.array([self.sample(t)[0] for t in ts])

    # ------------------------------------------------------------------------- checking ----
    def scene_matches(self, scene) -> bool:
        """True when ``scene`` holds the same objects as the scene this plan was made for."""
        return _rounded(describe_scene(scene)) == _rounded(self.scene)

    def check_robot(self, scene) -> None:
        """Raises unless the plan is for the scene's robot and planning group.

        Raises:
            PlanningError: INVALID_MOTION_PLAN naming both (a plan without a group, from a
                version 1 or 2 file, matches by robot name and joints).
        """
        model = scene.model
        mine = self.robot
        fingers = plan_robot(scene)["fingers"]
        same = (
            mine["name"] == model.robot.name
            and list(mine["joints"]) == model.joint_names
            and list(mine["fingers"]) == fingers
        )
        if same and (not mine.get("group") or mine["group"] == model.robot.group):
            return
        raise PlanningError(
            ErrorCode.INVALID_MOTION_PLAN,
            f"the plan is for {mine['name']} group {mine.get('group') or '?'} "
            f"({', '.join(mine['joints'])}); the scene's robot is {model.robot.name} group "
            f"{model.robot.group} ({', '.join(model.joint_names)})",
        )

    def validate(self, scene, resolution: float = 0.01, *, finger_positions=None) -> None:
        """Re-checks the path against ``scene`` (e.g. just before execution): the straight
        segments between the waypoints, and the trajectory itself where it is smoothed (within
        ``timing.path_tolerance`` of those segments).

        Args:
            scene: the ``PlanningScene`` now (its objects may have changed since planning).
            resolution: joint-space L2 distance between checked configurations, rad.
            finger_positions: (2,) m, the fingers during the check; the plan's when None (the
                check before motion passes the measured ones).

        Raises:
            PlanningError: INVALID_MOTION_PLAN naming the colliding bodies, or another robot's
                plan (``check_robot``).
        """
        self.check_robot(scene)
        saved = scene.finger_positions
        fingers = self.finger_positions if finger_positions is None else finger_positions
        scene.finger_positions = fingers
        try:
            adapter = CheckerAdapter(scene)
            bad = first_invalid_segment(adapter, self.waypoints, resolution)
            if bad is None:
                collision = self.smoothing_collision(adapter, resolution)
                if collision is not None:
                    (i, j), where = collision
                    raise PlanningError(
                        ErrorCode.INVALID_MOTION_PLAN,
                        f"the smoothed motion between waypoints {i} and {j} collides: "
                        f"{scene.describe_collisions(where)}",
                    )
                return
            from planning.paths import densify

            samples, segment = densify(self.waypoints[bad : bad + 2], resolution)
            where = next(q for q in samples if not scene.is_collision_free(q))
            raise PlanningError(
                ErrorCode.INVALID_MOTION_PLAN,
                f"segment {bad} of the plan collides: {scene.describe_collisions(where)}",
            )
        finally:
            scene.finger_positions = saved

    def smoothing_collision(self, adapter, resolution: float = 0.01):
        """Checks where the trajectory leaves the straight segments (its smoothed sections).

        Args:
            adapter: a collision adapter (``configs_free``) on the scene, fingers as planned.
            resolution: rad between checked configurations.

        Returns:
            None when those sections are collision-free, else ``((i, j), q)``: the section's
            first and last waypoint and a colliding configuration.
        """
        for i, j, samples in self._timing.smoothed_paths(resolution):
            free = adapter.configs_free(samples)
            if not free.all():
                return (i, j), samples[int(np.argmin(free))]
        return None

    # --------------------------------------------------------------------------- files ----
    def to_dict(self) -> dict:
        return {
            "format": FORMAT,
            "version": VERSION,
            "robot": self.robot,
            "waypoints": self.waypoints.tolist(),
            "max_velocity": self.max_velocity.tolist(),
            "max_acceleration": self.max_acceleration.tolist(),
            "velocity_scaling": float(self.velocity_scaling),
            "acceleration_scaling": float(self.acceleration_scaling),
            "finger_positions": self.finger_positions.tolist(),
            "scene": self.scene,
            "info": self.info,
            "timing": dc.asdict(self.timing),
        }

    @classmethod
    def from_dict(cls, data: dict, where: str = "plan") -> Plan:
        """Builds a plan from ``to_dict``'s form, every field checked first.

        Args:
            data: the decoded JSON of a plan file.
            where: how error messages name the source (a file name).

        Raises:
            PlanningError: INVALID_MOTION_PLAN naming the first field at fault (see
                ``planning.io.plan_files``), or saying that the fields give no finite timing.
        """
        fields = check_plan_data(data, where)
        fields["timing"] = RetimeOptions(**fields["timing"])
        try:
            with np.errstate(all="ignore"):
                plan = cls(**fields)
        # pydrake reports a failed internal condition (TOPP-RA on a degenerate path) as SystemExit.
        except (ValueError, RuntimeError, ArithmeticError, SystemExit) as e:
            first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
            message = first if first.startswith(_UNTIMEABLE) else f"{_UNTIMEABLE}: {first}"
            raise invalid(where, message) from e
        if not (np.isfinite(plan.duration) and np.all(np.isfinite(plan._timing.times))):
            message = f"the timing of the waypoints is not finite (duration {plan.duration} s)"
            raise invalid(where, message)
        return plan

    def save(self, filename: Path | str) -> None:
        """Writes the plan as JSON (see the module docstring), atomically."""
        write_atomic(filename, json.dumps(self.to_dict(), indent=1), "plan file")

    @classmethod
    def load(cls, filename: Path | str) -> Plan:
        """Reads a plan written by ``save``.

        Raises:
            PlanningError: INVALID_MOTION_PLAN naming the file (and the field at fault).
        """
        return cls.from_dict(read_plan_json(filename), str(filename))

    def __eq__(self, other) -> bool:
        if not isinstance(other, Plan):
            return NotImplemented
        return json.dumps(self.to_dict()) == json.dumps(other.to_dict())

    # ------------------------------------------------------------------------- display ----
    def plot(self, filename: Path | str, dt: float = 0.01, *, position_limits=None) -> None:
        """Writes a PNG of the joints' positions, velocities and accelerations against time,
        limits dashed (``planning.plan_plot.plot_plan``).

        Raises:
            RuntimeError: matplotlib is not installed.
        """
        from planning.plan_plot import plot_plan

        plot_plan(self, filename, dt, position_limits=position_limits)

    def replay(self, scene, *, dt: float = 0.02, realtime: bool = True) -> None:
        """Shows the motion in the scene's Meshcat (nothing when the scene has none)."""
        if scene.meshcat is None:
            return
        saved = scene.finger_positions
        scene.finger_positions = self.finger_positions
        try:
            start = time.perf_counter()
            for t, q in zip(*self.sample_many(dt), strict=True):
                if realtime:
                    time.sleep(max(0.0, start + t - time.perf_counter()))
                scene.publish(q)
        finally:
            scene.finger_positions = saved


def plan_robot(scene) -> dict:
    """The ``robot`` entry of a plan made in ``scene``: its robot's name, group and joints."""
    model = scene.model
    return {
        "name": model.robot.name,
        "group": model.robot.group,
        "joints": model.joint_names,
        "fingers": model.finger_names,
    }


def _rounded(value):
    if isinstance(value, float):
        return round(value, 9)
    if isinstance(value, list):
        return [_rounded(v) for v in value]
    if isinstance(value, dict):
        return {k: _rounded(v) for k, v in value.items()}
    return value


@dataclass
class PlanResult:
    """The outcome of a request.

    Attributes:
        success: true when the whole request was met with a validated path.
        trajectory: the timed ``Plan`` (for a partial Cartesian path, the part achieved).
        code: None on success, else the ``ErrorCode``.
        message: what happened.
        planning_time: wall time from request to validated path, s.
        fraction: share of a Cartesian path achieved (1 for other requests).
    """

    success: bool
    trajectory: Plan | None
    code: ErrorCode | None = None
    message: str = ""
    planning_time: float = 0.0
    fraction: float = 1.0

    @property
    def plan(self) -> Plan | None:
        return self.trajectory
