"""Shortest joint paths through IRIS regions with Graphs of Convex Sets, checked afterwards.

``GcsPlanner(scene, regions, options).plan(q_start, q_goal, deadline)`` builds a
``GcsTrajectoryOptimization`` over the regions (``planning.search.iris_regions``) in the 7 arm
joints: one Bezier curve of ``order`` per region visited, minimum path length (plus a small time
cost), solved by the convex relaxation with randomized rounding. The curve is sampled into waypoints
at most ``sample_step`` rad apart (for ``order`` 1 its pieces are straight: their ends suffice),
so the straight-line interpolation of the waypoints is the path.

Regions are only probabilistically collision-free, so the path is re-checked with the scene's
checker every ``validation_resolution`` rad. A colliding configuration q_c is cut out of every
region holding it by the half-space {q : a.q <= a.q_c - ``cut_margin``}, a = (q_c - c) / |q_c - c|
with c the region's Chebyshev centre (as IRIS separates a counterexample), and the problem is
solved again, at most ``max_repairs`` times; the cut regions are kept for later plans.

A start or goal outside every region is joined by a straight edge, checked at the validation
resolution, to a point just inside one of the ``connect_candidates`` nearest regions.

Reference:
    T. Marcucci, M. Petersen, D. von Wrangel, R. Tedrake, "Motion planning around obstacles
    with convex optimization", Science Robotics 2023.
"""

import dataclasses as dc
import time

import numpy as np

from planning.collision.checker import CheckerAdapter, first_invalid_segment
from planning.paths import densify, drop_duplicates, path_length


@dc.dataclass
class GcsOptions:
    """Options of ``GcsPlanner`` (units: rad, s)."""

    order: int = 1  # Bezier order per region (1: straight pieces)
    continuity: int = 0  # path-derivative continuity between pieces (needs order > continuity)
    time_cost: float = 0.01  # weight of the total time against the path length
    max_rounded_paths: int = 10  # roundings of the relaxation (measured: 1 to 5 gave longer paths)
    sample_step: float = 0.01  # rad, about the step between returned waypoints on curved pieces
    validation_resolution: float = 0.01  # rad between collision checks of the path
    max_repairs: int = 5  # cuts of colliding configurations out of regions, then re-solves
    cut_margin: float = 0.02  # rad by which a cut clears the colliding configuration
    connect_candidates: int = 3  # nearest regions tried for a start or goal outside them all
    max_velocity: list[float] = dc.field(
        default_factory=lambda: [2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61]
    )  # rad/s, bounds of the curve's time scaling


@dc.dataclass
class GcsResult:
    """The outcome of ``GcsPlanner.plan``.

    Attributes:
        success: true when ``path`` was found and passed the collision check.
        path: (N, n) waypoints, rad, whose straight-line interpolation is the checked path;
            None on failure.
        message: what happened (the colliding bodies when validation failed).
        solve_time: wall time, s.
        repairs: cuts of colliding configurations out of regions before the path validated.
    """

    success: bool
    path: np.ndarray | None
    message: str
    solve_time: float = 0.0
    repairs: int = 0

    @property
    def length(self) -> float:
        """Joint-space L2 length of the path, rad (inf without one)."""
        return float("inf") if self.path is None else path_length(self.path)


class GcsPlanner:
    """Plans in a static scene through precomputed regions.

    Args:
        scene: the ``PlanningScene`` the regions were grown in.
        regions: a ``RegionSet`` or a list of ``HPolyhedron`` in the 7 arm joints.
        options: ``GcsOptions()`` when None.
    """

    def __init__(self, scene, regions, options: GcsOptions | None = None):
        from pydrake.geometry.optimization import HPolyhedron

        self._scene = scene
        self._options = options if options is not None else GcsOptions()
        if self._options.order < 1 or self._options.continuity >= self._options.order:
            raise ValueError("GcsOptions needs order >= 1 and continuity < order")
        regions = getattr(regions, "regions", regions)
        self._regions = [HPolyhedron(r.A(), r.b()) for r in regions]
        if not self._regions:
            raise ValueError("GcsPlanner needs at least one region")
        self._centres = [r.ChebyshevCenter() for r in self._regions]
        self._fine = CheckerAdapter(scene, self._options.validation_resolution)

    @property
    def regions(self) -> list:
        """The regions, with the cuts made by repairs."""
        return list(self._regions)

    def plan(self, q_start, q_goal, deadline: float | None = None) -> GcsResult:
        """Returns a collision-checked path from q_start to q_goal (the group's joints, rad).

        Args:
            q_start, q_goal: collision-free configurations, rad.
            deadline: ``time.perf_counter()`` value after which no new solve starts.
        """
        t0 = time.perf_counter()
        deadline = float("inf") if deadline is None else deadline
        q_start, q_goal = (
            np.asarray(q, dtype=float).reshape(self._scene.num_joints) for q in (q_start, q_goal)
        )

        def fail(message: str, repairs: int = 0) -> GcsResult:
            return GcsResult(False, None, message, time.perf_counter() - t0, repairs)

        for q, what in ((q_start, "start"), (q_goal, "goal")):
            if not self._fine.config_free(q):
                return fail(f"the {what} collides: {self._scene.describe_collisions(q)}")
        for repairs in range(self._options.max_repairs + 1):
            if time.perf_counter() > deadline:
                return fail("timed out before GCS found a valid path", repairs)
            ends = [self._entry(q_start), self._entry(q_goal)]  # cuts may have moved them
            for q, what in zip(ends, ("start", "goal"), strict=True):
                if q is None:
                    return fail(f"the {what} is in no region and no straight edge reaches one")
            middle = self._solve(ends[0], ends[1])
            if middle is None:
                return fail(f"GCS found no path through the regions ({repairs} cuts)", repairs)
            path = drop_duplicates(np.vstack([q_start, middle, q_goal]), tolerance=1e-9)
            path[0], path[-1] = q_start, q_goal  # exactly
            bad = first_invalid_segment(self._fine, path, self._options.validation_resolution)
            if bad is None:
                return GcsResult(
                    True, path, "GCS path validated", time.perf_counter() - t0, repairs
                )
            samples, _ = densify(path[bad : bad + 2], self._options.validation_resolution)
            q_c = samples[~self._fine.configs_free(samples)][0]
            if not self._cut(q_c):
                break
        why = self._scene.describe_collisions(q_c)
        return fail(f"the GCS path collides ({why}) after {repairs} repairs", repairs)

    # ----------------------------------------------------------------------- internals ----
    def _entry(self, q) -> np.ndarray | None:
        """Returns q when a region holds it, else a point just inside a nearby region joined
        to q by a collision-free straight edge, else None."""
        if any(r.PointInSet(q, 1e-9) for r in self._regions):
            return q
        found = [r.Projection(q.reshape(-1, 1)) for r in self._regions]
        distances = [np.inf if f is None else f[0][0] for f in found]
        for i in np.argsort(distances)[: self._options.connect_candidates]:
            if not np.isfinite(distances[i]):
                break
            p = found[i][1][:, 0]
            inside = p + 1e-3 * (self._centres[i] - p)  # strictly inside: a GCS vertex
            if self._regions[i].PointInSet(inside, 1e-9) and self._fine.edge_free(q, inside):
                return inside
        return None

    def _solve(self, q_a, q_b) -> np.ndarray | None:
        """Returns the waypoints of the GCS curve from q_a to q_b, or None."""
        from pydrake.geometry.optimization import GraphOfConvexSetsOptions, Point
        from pydrake.planning import GcsTrajectoryOptimization

        opts = self._options
        gcs = GcsTrajectoryOptimization(self._scene.num_joints)
        main = gcs.AddRegions(self._regions, opts.order)
        source = gcs.AddRegions([Point(q_a)], 0)
        target = gcs.AddRegions([Point(q_b)], 0)
        gcs.AddEdges(source, main)
        gcs.AddEdges(main, target)
        gcs.AddPathLengthCost(1.0)
        gcs.AddTimeCost(opts.time_cost)
        v = np.asarray(opts.max_velocity, dtype=float)
        gcs.AddVelocityBounds(-v, v)
        if opts.continuity > 0:
            gcs.AddPathContinuityConstraints(opts.continuity)
        solver_options = GraphOfConvexSetsOptions()
        solver_options.convex_relaxation = True
        solver_options.max_rounded_paths = opts.max_rounded_paths
        solver_options.rounding_seed = 0
        trajectory, result = gcs.SolvePath(source, target, solver_options)
        if not result.is_success():
            return None
        return self._sample(trajectory)

    def _sample(self, trajectory) -> np.ndarray:
        points = []
        for i in range(trajectory.get_number_of_segments()):
            segment = trajectory.segment(i)
            t_a, t_b = segment.start_time(), segment.end_time()
            n = 1
            if self._options.order > 1:  # curved: steps of at most sample_step
                coarse = np.column_stack([segment.value(t) for t in np.linspace(t_a, t_b, 33)])
                n = max(1, int(np.ceil(path_length(coarse.T) / self._options.sample_step)))
            points += [segment.value(t)[:, 0] for t in np.linspace(t_a, t_b, n + 1)]
        return np.array(points)

    def _cut(self, q_c) -> bool:
        """Cuts q_c (and cut_margin around it) out of the regions holding it; False when none
        holds it (the collision is on a connecting edge or between regions)."""
        from pydrake.geometry.optimization import HPolyhedron

        cut = False
        for i, r in enumerate(self._regions):
            if not r.PointInSet(q_c, 1e-9):
                continue
            a = q_c - self._centres[i]
            a /= np.linalg.norm(a)
            b = a @ q_c - self._options.cut_margin
            self._regions[i] = HPolyhedron(np.vstack([r.A(), a]), np.append(r.b(), b))
            cut = True
        return cut


class SceneGcs:
    """A ``GcsPlanner`` used only while the scene is the one its regions were grown in.

    Args:
        scene: the ``PlanningScene``.
        regions: a ``planning.search.iris_regions.RegionSet`` (its ``key`` names the scene it fits).
        region_options: the ``RegionOptions`` they were grown with (defaults when None).
        options: ``GcsOptions``.
    """

    def __init__(self, scene, regions, region_options=None, options: GcsOptions | None = None):
        from planning.search.iris_regions import RegionOptions

        self._scene, self._regions = scene, regions
        self._region_options = region_options or RegionOptions()
        self._planner = GcsPlanner(scene, regions, options)

    def path(self, q_start, q_goal, deadline: float) -> np.ndarray | None:
        """A validated GCS path, or None when it fails or the scene changed since the regions
        were grown (same cache key as ``planning.search.iris_regions.region_key``)."""
        from planning.search.iris_regions import region_key

        key = region_key(self._scene, self._regions.seeds, self._region_options)
        if key != self._regions.key:
            return None
        result = self._planner.plan(q_start, q_goal, deadline)
        return result.path if result.success else None
