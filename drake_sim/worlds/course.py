"""Wall-E's line-following courses: the YAML schema, its checks, and the centreline's geometry.

A course (``config/courses/*.yaml``, the contract in DESIGN.md) is a white line on a black floor
whose centreline starts at a pose and runs through straights and circular arcs:

.. code-block:: yaml

    line_width: 0.03        # m
    floor_margin: 0.5       # m of floor around the line's bounding box
    closed: true            # a loop (its end meets its start within 1 cm) or an open path
    start: {x: 0.0, y: 0.0, yaw: 0.0}      # m, m, degrees
    segments:
      - {straight: 1.5}                    # m
      - {arc: {radius: 0.6, angle: 180}}   # m, degrees; positive turns left

``load_course`` reads and checks one; ``centreline`` samples its centreline densely in the world
frame W (x, y on the floor, z up), with the arc length, heading and curvature at every sample,
and answers the questions a run's report asks: how far a point is from the line and where along
it (``Centreline.project``), and how far a robot has moved along a loop (``Centreline.advance``).
"""

import dataclasses as dc
import math
from pathlib import Path

import numpy as np

from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError
from drake_sim.base.planar import wrap_angle_exact
from drake_sim.base.resources import config_dir

CLOSE_TOLERANCE = 0.01
"""m: how near a closed course's end must come to its start."""

SAMPLE_SPACING = 0.005
"""m: the default arc-length step between centreline samples."""


@dc.dataclass
class StartPose:
    """Where the centreline starts, in the world frame W."""

    x: float = 0.0  # m.
    y: float = 0.0  # m.
    yaw: float = 0.0  # degrees, the line's heading from W's x axis, counter-clockwise.


@dc.dataclass
class ArcSpec:
    """A circular arc of the centreline."""

    radius: float = math.nan  # m, > 0.
    angle: float = math.nan  # degrees turned, non-zero; positive turns left.


@dc.dataclass
class SegmentSpec:
    """One piece of the centreline: exactly one of ``straight`` and ``arc``."""

    straight: float | None = None  # m, > 0: a straight of this length.
    arc: ArcSpec | None = None


@dc.dataclass
class Course:
    """A line-following course: a white line of ``line_width`` on a black floor."""

    line_width: float = 0.03  # m, > 0.
    floor_margin: float = 0.5  # m, >= 0: floor around the line's bounding box.
    closed: bool = False  # A loop (end within CLOSE_TOLERANCE of start) or an open path.
    start: StartPose = dc.field(default_factory=StartPose)
    segments: list[SegmentSpec] = dc.field(default_factory=list)  # In order from the start.


def load_course(filename: Path | str) -> Course:
    """Loads and checks a course file.

    Raises:
        ConfigError: naming the file and the key, for a malformed file, an unknown key, a
            non-finite number, a zero or negative length, a segment that is neither or both of
            ``straight`` and ``arc``, no segments, or a loop marked ``closed`` that does not close.
    """
    course = load_typed(Course, filename=filename)
    return check_course(course, str(filename))


def shipped_courses() -> list[Path]:
    """Returns the course files shipped in ``config/courses/``, sorted by name."""
    return sorted((config_dir() / "courses").glob("*.yaml"))


def check_course(course: Course, where: str = "course") -> Course:
    """Returns ``course`` if it is valid; raises ``ConfigError`` naming ``where`` and the key."""
    for key in ("line_width", "floor_margin"):
        value = getattr(course, key)
        if not math.isfinite(value) or value < 0 or (key == "line_width" and value == 0):
            bound = "positive" if key == "line_width" else "zero or positive"
            raise ConfigError(f"{where}: '{key}' must be {bound}, got {value!r}")
    for key in ("x", "y", "yaw"):
        if not math.isfinite(getattr(course.start, key)):
            raise ConfigError(f"{where}: 'start.{key}' must be finite")
    if not course.segments:
        raise ConfigError(f"{where}: 'segments' is empty; a course needs at least one segment")
    for i, segment in enumerate(course.segments):
        _check_segment(segment, where, f"segments[{i}]")
    if course.closed:
        samples = _walk(course)
        gap = float(np.linalg.norm(samples[-1, :2] - samples[0, :2]))
        if gap > CLOSE_TOLERANCE:
            raise ConfigError(
                f"{where}: 'closed' is true but the segments end {gap:.3f} m from the start "
                f"(at most {CLOSE_TOLERANCE} m)"
            )
    return course


def _check_segment(segment: SegmentSpec, where: str, name: str) -> None:
    if (segment.straight is None) == (segment.arc is None):
        raise ConfigError(f"{where}: '{name}' must have exactly one of 'straight' and 'arc'")
    if segment.straight is not None:
        _check_positive(segment.straight, where, f"{name}.straight")
        return
    _check_positive(segment.arc.radius, where, f"{name}.arc.radius")
    angle = segment.arc.angle
    if math.isnan(angle):
        raise ConfigError(f"{where}: missing key '{name}.arc.angle'")
    if not math.isfinite(angle) or angle == 0:
        raise ConfigError(f"{where}: '{name}.arc.angle' must be non-zero, got {angle!r}")


def _check_positive(value: float, where: str, name: str) -> None:
    if math.isnan(value):
        raise ConfigError(f"{where}: missing key '{name}'")
    if not (math.isfinite(value) and value > 0):
        raise ConfigError(f"{where}: '{name}' must be positive, got {value!r}")


def _walk(course: Course, spacing: float = SAMPLE_SPACING) -> np.ndarray:
    """Returns (n, 5) samples ``[x, y, heading, s, curvature]`` along the course's segments
    (m, m, rad unwrapped, m, 1/m); each segment's curvature is on the samples it starts."""
    x, y = course.start.x, course.start.y
    heading, s = math.radians(course.start.yaw), 0.0
    rows = [[x, y, heading, s, 0.0]]
    for segment in course.segments:
        if segment.straight is not None:
            length, turn, kappa = segment.straight, 0.0, 0.0
        else:
            turn = math.radians(segment.arc.angle)
            length = segment.arc.radius * abs(turn)
            kappa = math.copysign(1.0 / segment.arc.radius, turn)
        rows[-1][4] = kappa
        n = max(1, math.ceil(length / spacing))
        for k in range(1, n + 1):
            u = length * k / n
            phi = kappa * u  # heading change so far, rad
            if kappa == 0.0:
                px, py = x + u * math.cos(heading), y + u * math.sin(heading)
            else:
                r = 1.0 / kappa  # signed radius: the centre is r along the left normal
                px = x + r * (math.sin(heading + phi) - math.sin(heading))
                py = y - r * (math.cos(heading + phi) - math.cos(heading))
            rows.append([px, py, heading + phi, s + u, kappa])
        x, y, heading, s = px, py, heading + turn, s + length
    rows[-1][4] = 0.0
    return np.array(rows)


@dc.dataclass(frozen=True)
class Projection:
    """Where a point Q projects onto the centreline (its nearest point F on it)."""

    s: float  # m, arc length of F from the start.
    distance: float  # m, |p_WQ - p_WF|.
    offset: float  # m, signed: positive when Q is to the left of the line's direction.
    heading: float  # rad, the line's direction at F from W's x axis, in [-pi, pi).
    p_WF: np.ndarray  # (2,) m, F in the world frame.


@dc.dataclass(frozen=True)
class Centreline:
    """A course's centreline as a dense polyline in the world frame W (z = 0).

    ``p_WP[i]`` is the i-th sample (m), ``s[i]`` its arc length from the start (m), ``heading[i]``
    the line's direction there (rad, unwrapped, counter-clockwise from W's x axis) and
    ``curvature[i]`` that of the segment beginning at it (1/m, positive turning left). A closed
    course's last sample is its first point again.
    """

    p_WP: np.ndarray
    s: np.ndarray
    heading: np.ndarray
    curvature: np.ndarray
    closed: bool

    @property
    def length(self) -> float:
        """Total arc length, m."""
        return float(self.s[-1])

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Returns the lower and upper (x, y) corners of the samples' bounding box, m."""
        return self.p_WP.min(axis=0), self.p_WP.max(axis=0)

    def pose_at(self, s: float) -> tuple[np.ndarray, float]:
        """Returns the point p_WP (m) and heading (rad) at arc length ``s`` (wrapped on a loop,
        clamped on an open path)."""
        s = s % self.length if self.closed else min(max(s, 0.0), self.length)
        p = np.array([np.interp(s, self.s, self.p_WP[:, k]) for k in range(2)])
        return p, wrap_angle_exact(float(np.interp(s, self.s, self.heading)))

    def distances(self, p_WQ: np.ndarray) -> np.ndarray:
        """Returns the distance (m) from each of the (m, 2) points ``p_WQ`` to the line."""
        _, _, d2 = self._nearest(np.atleast_2d(np.asarray(p_WQ, dtype=float))[:, :2])
        return np.sqrt(d2)

    def project(self, p_WQ) -> Projection:
        """Projects the point ``p_WQ`` (x, y; a z is ignored) onto the nearest point of the line."""
        q = np.asarray(p_WQ, dtype=float)[:2]
        index, t, d2 = self._nearest(q[None, :])
        i, t = int(index[0]), float(t[0])
        a, b = self.p_WP[i], self.p_WP[i + 1]
        foot = a + t * (b - a)
        heading = self.heading[i] + t * (self.heading[i + 1] - self.heading[i])
        direction = b - a
        cross = direction[0] * (q[1] - foot[1]) - direction[1] * (q[0] - foot[0])
        distance = math.sqrt(float(d2[0]))
        return Projection(
            s=float(self.s[i] + t * (self.s[i + 1] - self.s[i])),
            distance=distance,
            offset=math.copysign(distance, cross),
            heading=wrap_angle_exact(float(heading)),
            p_WF=foot,
        )

    def advance(self, s_from: float, s_to: float) -> float:
        """Returns the signed arc length (m) travelled from ``s_from`` to ``s_to``: on a loop the
        shorter way round (so crossing the start counts as a small step, not a whole lap)."""
        ds = s_to - s_from
        if self.closed:
            ds = (ds + 0.5 * self.length) % self.length - 0.5 * self.length
        return ds

    def _nearest(self, q: np.ndarray):
        return nearest_on_chords(q, self.p_WP[:-1], self.p_WP[1:])


def nearest_on_chords(q: np.ndarray, a: np.ndarray, b: np.ndarray):
    """For each of the (m, 2) points ``q``, the nearest of the n chords from ``a[k]`` to ``b[k]``
    ((n, 2) each, m): returns its index, the fraction along it of the nearest point, and the
    squared distance to it (m^2), each of shape (m,)."""
    ab = b - a
    ab2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-18)
    aq = q[:, None, :] - a[None, :, :]
    t = np.clip(np.einsum("mij,ij->mi", aq, ab) / ab2, 0.0, 1.0)
    diff = aq - t[..., None] * ab[None, :, :]
    d2 = np.einsum("mij,mij->mi", diff, diff)
    index = np.argmin(d2, axis=1)
    rows = np.arange(len(q))
    return index, t[rows, index], d2[rows, index]


def centreline(course: Course, spacing: float = SAMPLE_SPACING) -> Centreline:
    """Samples ``course``'s centreline every ``spacing`` m (at most) of arc length.

    A closed course's samples end with its start point (so a loop that ends within
    ``CLOSE_TOLERANCE`` of its start is joined by one short chord).
    """
    rows = _walk(course, spacing)
    if course.closed:
        gap = float(np.linalg.norm(rows[-1, :2] - rows[0, :2]))
        if gap > 1e-9:
            rows = np.vstack([rows, [*rows[0, :2], rows[-1, 2], rows[-1, 3] + gap, 0.0]])
        else:
            rows[-1, :2] = rows[0, :2]
    return Centreline(
        p_WP=rows[:, :2].copy(),
        s=rows[:, 3].copy(),
        heading=rows[:, 2].copy(),
        curvature=rows[:, 4].copy(),
        closed=course.closed,
    )
