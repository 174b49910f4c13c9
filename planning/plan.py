"""A planned motion: a timed joint trajectory that remembers the scene and robot it was made for.

File format (JSON, one object; ``Plan.save`` / ``Plan.load``)::

    {
      "format": "drake_sim.plan", "version": 1,
      "robot": {"name": "panda", "joints": ["panda_joint1", ...]},
      "waypoints": [[q1..q7], ...],            # rad, the collision-checked path
      "max_velocity": [7 values],              # rad/s, limits after scaling
      "max_acceleration": [7 values],          # rad/s^2, limits after scaling
      "velocity_scaling": 1.0, "acceleration_scaling": 1.0,
      "finger_positions": [f1, f2],            # m, held during the motion
      "scene": {"world": [object, ...], "attached": [object, ...]},
      "info": {...}                            # free-form: planner, planning time, ...
    }

where an object is ``{"name", "shape", "size", "position", "orientation": [x, y, z, w]}`` as in
``scene_objects`` (world objects: pose X_WO; attached ones: X_AO in the hand's attachment frame).
Times are not stored: they follow from the waypoints and limits (``planning._retime``), so a
loaded plan samples exactly as the saved one. Floats are written with ``repr`` precision, so a
plan loads back equal.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from planning._retime import sample_segment, segment_profiles
from planning._rrt import CheckerAdapter, first_invalid_segment
from planning.errors import ErrorCode, PlanningError
from planning.panda_model import ARM_JOINTS

_FORMAT = "drake_sim.plan"


def describe_scene(scene) -> dict:
    """Returns a JSON-ready description of a scene's world and attached objects."""

    def entry(obj) -> dict:
        quat = obj.X_PO.rotation().ToQuaternion()
        return {
            "name": obj.name,
            "shape": obj.shape,
            "size": [float(s) for s in obj.size],
            "position": obj.X_PO.translation().tolist(),
            "orientation": [quat.x(), quat.y(), quat.z(), quat.w()],
        }

    return {
        "world": [entry(o) for o in scene.world_objects.values()],
        "attached": [entry(o) for o in scene.attached_objects.values()],
    }


@dataclass
class Plan:
    """A rest-to-rest timed trajectory through joint waypoints (see ``planning._retime``).

    Attributes:
        waypoints: (N, 7) arm joints, rad; the straight-line interpolation is the checked path.
        max_velocity: (7,) joint speed limits used, rad/s (already scaled).
        max_acceleration: (7,) joint acceleration limits used, rad/s^2 (already scaled).
        velocity_scaling, acceleration_scaling: the factors applied to the robot's limits.
        finger_positions: (2,) m, during the motion.
        scene: ``describe_scene`` of the scene it was planned in.
        robot: name and joint names.
        info: free-form facts (planner, planning time, path length, ...).
    """

    waypoints: np.ndarray
    max_velocity: np.ndarray
    max_acceleration: np.ndarray
    velocity_scaling: float = 1.0
    acceleration_scaling: float = 1.0
    finger_positions: np.ndarray = field(default_factory=lambda: np.full(2, 0.04))
    scene: dict = field(default_factory=lambda: {"world": [], "attached": []})
    robot: dict = field(default_factory=lambda: {"name": "panda", "joints": list(ARM_JOINTS)})
    info: dict = field(default_factory=dict)

    def __post_init__(self):
        self.waypoints = np.atleast_2d(np.asarray(self.waypoints, dtype=float))
        self.max_velocity = np.asarray(self.max_velocity, dtype=float)
        self.max_acceleration = np.asarray(self.max_acceleration, dtype=float)
        self.finger_positions = np.asarray(self.finger_positions, dtype=float)
        if self.waypoints.shape[1] != 7 or len(self.waypoints) < 1:
            raise ValueError(f"waypoints must be (N, 7), got {self.waypoints.shape}")
        if np.any(self.max_velocity <= 0) or np.any(self.max_acceleration <= 0):
            raise ValueError("velocity and acceleration limits must be positive")
        self._durations, self._ramps, self._accels = segment_profiles(
            self.waypoints, self.max_velocity, self.max_acceleration
        )
        self._times = np.concatenate([[0.0], np.cumsum(self._durations)])

    # ------------------------------------------------------------------------- inspect ----
    @property
    def duration(self) -> float:
        """Total time, s."""
        return float(self._times[-1])

    @property
    def times(self) -> np.ndarray:
        """Time at each waypoint, s (the robot is at rest there)."""
        return self._times.copy()

    @property
    def path_length(self) -> float:
        """Joint-space L2 length, rad."""
        return float(np.linalg.norm(np.diff(self.waypoints, axis=0), axis=1).sum())

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Returns (q rad, v rad/s, a rad/s^2) of the 7 arm joints at time t (clamped)."""
        if len(self.waypoints) == 1 or t >= self.duration:
            return self.waypoints[-1].copy(), np.zeros(7), np.zeros(7)
        t = max(t, 0.0)
        k = int(np.searchsorted(self._times, t, side="right") - 1)
        k = min(k, len(self._durations) - 1)
        s, s_dot, s_ddot = sample_segment(
            t - self._times[k], self._durations[k], self._ramps[k], self._accels[k]
        )
        d = self.waypoints[k + 1] - self.waypoints[k]
        return self.waypoints[k] + s * d, s_dot * d, s_ddot * d

    def sample_many(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Returns (times (M,), q (M, 7)) every dt seconds, the end included."""
        ts = np.append(np.arange(0.0, self.duration, dt), self.duration)
        return ts, np.array([self.sample(t)[0] for t in ts])

    # ------------------------------------------------------------------------- checking ----
    def scene_matches(self, scene) -> bool:
        """True when ``scene`` holds the same objects as the scene this plan was made for."""
        return _rounded(describe_scene(scene)) == _rounded(self.scene)

    def validate(self, scene, resolution: float = 0.01) -> None:
        """Re-checks the path against ``scene`` (e.g. just before execution).

        Args:
            scene: the ``PlanningScene`` now (its objects may have changed since planning).
            resolution: joint-space L2 distance between checked configurations, rad.

        Raises:
            PlanningError: INVALID_MOTION_PLAN naming the colliding bodies.
        """
        saved = scene.finger_positions
        scene.finger_positions = self.finger_positions
        try:
            bad = first_invalid_segment(CheckerAdapter(scene), self.waypoints, resolution)
            if bad is None:
                return
            from planning._rrt import densify

            samples, segment = densify(self.waypoints[bad : bad + 2], resolution)
            where = next(q for q in samples if not scene.is_collision_free(q))
            raise PlanningError(
                ErrorCode.INVALID_MOTION_PLAN,
                f"segment {bad} of the plan collides: {scene.describe_collisions(where)}",
            )
        finally:
            scene.finger_positions = saved

    # --------------------------------------------------------------------------- files ----
    def to_dict(self) -> dict:
        return {
            "format": _FORMAT,
            "version": 1,
            "robot": self.robot,
            "waypoints": self.waypoints.tolist(),
            "max_velocity": self.max_velocity.tolist(),
            "max_acceleration": self.max_acceleration.tolist(),
            "velocity_scaling": float(self.velocity_scaling),
            "acceleration_scaling": float(self.acceleration_scaling),
            "finger_positions": self.finger_positions.tolist(),
            "scene": self.scene,
            "info": self.info,
        }

    @classmethod
    def from_dict(cls, data: dict) -> Plan:
        if data.get("format") != _FORMAT:
            raise ValueError(f"not a plan file (format {data.get('format')!r})")
        keys = [
            "waypoints",
            "max_velocity",
            "max_acceleration",
            "velocity_scaling",
            "acceleration_scaling",
            "finger_positions",
            "scene",
            "robot",
            "info",
        ]
        return cls(**{k: data[k] for k in keys if k in data})

    def save(self, filename: Path | str) -> None:
        """Writes the plan as JSON (see the module docstring)."""
        Path(filename).write_text(json.dumps(self.to_dict(), indent=1))

    @classmethod
    def load(cls, filename: Path | str) -> Plan:
        """Reads a plan written by ``save``."""
        return cls.from_dict(json.loads(Path(filename).read_text()))

    def __eq__(self, other) -> bool:
        if not isinstance(other, Plan):
            return NotImplemented
        return json.dumps(self.to_dict()) == json.dumps(other.to_dict())

    # ------------------------------------------------------------------------- display ----
    def plot(self, filename: Path | str, dt: float = 0.01) -> None:
        """Writes a PNG of the joint positions (rad) against time (s).

        Raises:
            RuntimeError: matplotlib is not installed.
        """
        try:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
        except ImportError as e:
            raise RuntimeError("Plan.plot needs matplotlib (pip install matplotlib)") from e
        ts, qs = self.sample_many(dt)
        fig, ax = plt.subplots(figsize=(8, 4.5))
        for j, name in enumerate(self.robot.get("joints", ARM_JOINTS)):
            ax.plot(ts, qs[:, j], label=name)
        ax.plot(self._times, self.waypoints, "k.", markersize=4)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("joint position (rad)")
        ax.legend(fontsize=7, loc="best")
        ax.grid(True, alpha=0.3)
        fig.tight_layout()
        fig.savefig(filename, dpi=100)
        plt.close(fig)

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


def _rounded(value):
    if isinstance(value, float):
        return round(value, 9)
    if isinstance(value, list):
        return [_rounded(v) for v in value]
    if isinstance(value, dict):
        return {k: _rounded(v) for k, v in value.items()}
    return value
