"""Convex collision-free regions of the Panda's arm configuration space, cached on disk.

Regions are grown with IRIS-ZO (``pydrake.planning.IrisZo``) on the scene's
``SceneGraphCollisionChecker``, so the objects added to the scene at run time are seen (IrisNp2
queries the SceneGraph, which does not hold them). They live in the 7 arm joints (rad); the
fingers stay at the scene's ``finger_positions`` through a constant parameterization. A region
is only *probabilistically* collision-free: at most ``epsilon`` of its volume collides, with
probability at least 1 - ``delta``; paths through regions must be checked again.

Growth (``build_regions``): every seed (e.g. named configurations and the user's waypoints)
gets a region unless one already contains it. With ``connect``, consecutive seeds are then joined
by a collision-free path (the straight line, else RRT-Connect from ``planning.search.rrt``), sampled
every ``connect_step`` rad; where a sample q_{k+1} leaves the region holding q_k, a region that
holds both is found or grown (IRIS-ZO ``containment_points``), so consecutive regions share a
point and the graph of regions is connected along the route.

Cache (``load_or_build_regions``): ``cache_dir()/iris_regions/<key>.npz`` holds, for region i,
arrays ``A_i`` (m_i, 7) and ``b_i`` (m_i,) of {q : A_i q <= b_i}, the ``seeds`` (n, 7) and a JSON
``meta`` string. The key is a SHA-256 of the scene description
(``planning.scene_objects.describe_scene``), the finger positions, the robot model options, the
seeds (rounded to 1e-6 rad), the options and Drake's version, so a changed scene, seed or option
builds new regions.
"""

import dataclasses as dc
import hashlib
import json
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from drake_sim.base.resources import cache_dir

_FORMAT = 1


@dc.dataclass
class RegionOptions:
    """How regions are grown (IRIS-ZO's parameters and the covering of the seeds)."""

    epsilon: float = 0.02  # admissible fraction of a region's volume in collision
    delta: float = 0.1  # admissible probability that more than epsilon collides
    num_particles: int = 500  # collision samples per IRIS-ZO iteration
    max_iterations: int = 2  # IRIS-ZO outer iterations per region
    bisection_steps: int = 8  # steps towards the boundary per colliding particle
    configuration_space_margin: float = 0.01  # rad kept from the obstacles found
    seed_radius: float = 0.01  # rad, radius of the starting ball around a seed
    # rad, half-width of the box around a seed that bounds its region (within the joint
    # limits): small regions make thin obstacles a larger share of the volume IRIS-ZO samples.
    max_half_width: float = 0.5
    connect: bool = True  # grow regions along collision-free paths between consecutive seeds
    connect_step: float = 0.05  # rad between path samples when connecting seeds
    connect_timeout: float = 10.0  # s for RRT-Connect between two seeds
    max_regions: int = 40  # stop growing after this many regions
    random_seed: int = 0  # IRIS-ZO's and RRT-Connect's seed


def check_region_options(options: RegionOptions) -> None:
    """Raises ValueError for options IRIS-ZO cannot use."""
    o = options
    positive = [o.epsilon, o.delta, o.num_particles, o.max_iterations, o.seed_radius]
    positive += [o.max_half_width, o.connect_step, o.connect_timeout, o.max_regions]
    if min(positive) <= 0 or o.epsilon >= 1 or o.delta >= 1 or o.bisection_steps < 1:
        raise ValueError(f"bad RegionOptions: {o}")


@dc.dataclass
class RegionSet:
    """Regions with where they came from.

    Attributes:
        regions: the ``HPolyhedron`` regions in the 7 arm joints, rad.
        seeds: (n, 7) the configurations they were grown to cover, rad.
        key: the cache key.
        path: the cache file (None when not cached).
        loaded: true when read from the cache instead of built.
        build_time: wall time spent growing them, s (as recorded when built).
    """

    regions: list
    seeds: np.ndarray
    key: str
    path: Path | None = None
    loaded: bool = False
    build_time: float = 0.0

    def containing(self, q) -> list[int]:
        """Indices of the regions that contain q (7 arm joints, rad)."""
        return [i for i, r in enumerate(self.regions) if r.PointInSet(q, 1e-9)]


def region_key(scene, seeds, options: RegionOptions) -> str:
    """Returns the cache key of regions grown for ``seeds`` in ``scene`` with ``options``."""
    import pydrake

    from planning.scene_objects import describe_scene

    data = {
        "format": _FORMAT,
        "scene": describe_scene(scene),
        "fingers": np.round(scene.other_positions, 9).tolist(),
        "model": dc.asdict(scene.config.model),
        "seeds": np.round(np.asarray(seeds, dtype=float), 6).tolist(),
        "options": dc.asdict(options),
        "drake": getattr(pydrake, "__version__", "unknown"),
    }
    text = json.dumps(data, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def load_or_build_regions(
    scene,
    seeds,
    options: RegionOptions | None = None,
    *,
    folder: Path | None = None,
    progress: Callable[[str], None] | None = None,
) -> RegionSet:
    """Returns the regions for ``seeds`` in ``scene``, from the cache when there, else grown
    with ``build_regions`` and saved.

    Args:
        scene: the ``PlanningScene`` (static while the regions are used).
        seeds: (n, 7) collision-free arm configurations, rad, in route order.
        options: how to grow; ``RegionOptions()`` when None.
        folder: the cache folder; ``cache_dir()/iris_regions`` when None.
        progress: called with one line of text per step.

    Raises:
        ValueError: bad options, or a seed has the wrong shape, is out of limits or collides.
        RuntimeError: IRIS-ZO failed, no path joins two seeds, or ``max_regions`` is too few.
    """
    options = options if options is not None else RegionOptions()
    check_region_options(options)
    seeds = _check_seeds(scene, seeds)
    key = region_key(scene, seeds, options)
    path = (folder or cache_dir() / "iris_regions") / f"{key}.npz"
    if path.is_file():
        regions, meta = _read(path)
        return RegionSet(regions, seeds, key, path, True, meta.get("build_time", 0.0))
    start = time.perf_counter()
    regions = build_regions(scene, seeds, options, progress=progress)
    build_time = time.perf_counter() - start
    _write(path, regions, seeds, {"key": key, "build_time": build_time})
    return RegionSet(regions, seeds, key, path, False, build_time)


def build_regions(
    scene, seeds, options: RegionOptions, *, progress: Callable[[str], None] | None = None
) -> list:
    """Grows regions covering every seed and, with ``options.connect``, the routes between
    consecutive seeds (see the module docstring). Returns a list of ``HPolyhedron``."""
    grower = _Grower(scene, options, progress or (lambda line: None))
    seeds = _check_seeds(scene, seeds)
    for q in seeds:
        if not grower.containing(q):
            grower.grow(q)
    if options.connect:
        for q_a, q_b in zip(seeds[:-1], seeds[1:], strict=True):
            grower.cover_route(q_a, q_b)
    return grower.regions


class _Grower:
    """IRIS-ZO on the scene's checker, in the arm joints, with the fingers held fixed."""

    def __init__(self, scene, options: RegionOptions, progress):
        from pydrake.planning import IrisParameterizationFunction, IrisZoOptions
        from pydrake.symbolic import Expression, Variable

        from planning.collision.checker import CheckerAdapter

        self._scene, self._options, self._progress = scene, options, progress
        self._adapter = CheckerAdapter(scene)
        x = [Variable(f"q{i}") for i in range(scene.num_joints)]
        full = [Expression(0.0)] * scene.plant.num_positions()
        for k, i in enumerate(scene.model.arm_indices):
            full[i] = Expression(x[k])
        for f, i in zip(scene.other_positions, scene.model.other_indices, strict=True):
            full[i] = Expression(float(f))
        self._iris = IrisZoOptions()
        self._iris.parameterization = IrisParameterizationFunction(np.array(full), np.array(x))
        self._iris.bisection_steps = options.bisection_steps
        common = self._iris.sampled_iris_options
        common.epsilon, common.delta = options.epsilon, options.delta
        common.num_particles = options.num_particles
        common.max_iterations = options.max_iterations
        common.configuration_space_margin = options.configuration_space_margin
        common.random_seed = options.random_seed
        self.regions: list = []

    def containing(self, q) -> list:
        return [r for r in self.regions if r.PointInSet(q, 1e-9)]

    def grow(self, q, contain=None):
        """Grows a region around q (and containing the columns of ``contain``, 7 x k)."""
        from pydrake.geometry.optimization import HPolyhedron, Hyperellipsoid
        from pydrake.planning import IrisZo

        if len(self.regions) >= self._options.max_regions:
            raise RuntimeError(f"more than max_regions={self._options.max_regions} regions needed")
        start = time.perf_counter()
        common = self._iris.sampled_iris_options
        common.containment_points = contain
        ball = Hyperellipsoid.MakeHypersphere(self._options.seed_radius, q)
        w = self._options.max_half_width
        lower = np.maximum(self._adapter.lower, q - w)
        upper = np.minimum(self._adapter.upper, q + w)
        if contain is not None:
            lower = np.minimum(lower, contain.min(axis=1))
            upper = np.maximum(upper, contain.max(axis=1))
        domain = HPolyhedron.MakeBox(lower, upper)
        region = IrisZo(self._scene.checker, ball, domain, self._iris).ReduceInequalities()
        common.containment_points = None
        self.regions.append(region)
        self._progress(
            f"region {len(self.regions)}: {region.A().shape[0]} faces, "
            f"{time.perf_counter() - start:.1f} s"
        )
        return region

    def cover_route(self, q_a, q_b) -> None:
        """Makes the regions cover a collision-free path from q_a to q_b, consecutive regions
        sharing a path sample."""
        from planning.paths import densify
        from planning.search.rrt import rrt_connect

        path = np.vstack([q_a, q_b])
        if not self._adapter.edge_free(q_a, q_b):
            rng = np.random.default_rng(self._options.random_seed)
            deadline = time.perf_counter() + self._options.connect_timeout
            path = rrt_connect(
                self._adapter, q_a, q_b, step=0.5, goal_bias=0.05, deadline=deadline, rng=rng
            )
            if path is None:
                raise RuntimeError("no collision-free path found between two seeds")
        samples, _ = densify(path, self._options.connect_step)
        current = self.containing(samples[0])[0]
        for q_prev, q in zip(samples[:-1], samples[1:], strict=True):
            if current.PointInSet(q, 1e-9):
                continue
            both = [r for r in self.containing(q) if r.PointInSet(q_prev, 1e-9)]
            current = both[0] if both else self.grow(q, np.column_stack([q_prev, q]))


def _check_seeds(scene, seeds) -> np.ndarray:
    seeds = np.atleast_2d(np.asarray(seeds, dtype=float))
    n = scene.num_joints
    if seeds.ndim != 2 or seeds.shape[1] != n or len(seeds) == 0:
        raise ValueError(f"seeds must be (k, {n}) configurations, got shape {seeds.shape}")
    for i, q in enumerate(seeds):
        if not np.all(np.isfinite(q)) or not scene.in_joint_limits(q, tolerance=1e-9):
            raise ValueError(f"seed {i} {np.round(q, 4).tolist()} is out of the joint limits")
        if not scene.is_collision_free(q):
            raise ValueError(f"seed {i} collides: {scene.describe_collisions(q)}")
    return seeds


def _write(path: Path, regions, seeds, meta: dict) -> None:
    arrays = {"seeds": seeds, "meta": np.array(json.dumps(meta))}
    for i, r in enumerate(regions):
        arrays[f"A_{i}"], arrays[f"b_{i}"] = r.A(), r.b()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp.npz")
    np.savez(tmp, **arrays)
    tmp.replace(path)


def _read(path: Path) -> tuple[list, dict]:
    from pydrake.geometry.optimization import HPolyhedron

    with np.load(path) as data:
        n = sum(1 for name in data.files if name.startswith("A_"))
        regions = [HPolyhedron(data[f"A_{i}"], data[f"b_{i}"]) for i in range(n)]
        meta = json.loads(str(data["meta"]))
    return regions, meta
