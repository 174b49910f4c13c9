"""The compiled sphere kernel (planning.collision.sphere_kernel)."""

import importlib.util
import types
import uuid

import numba.core.config
import numpy as np
import pytest
from numba import njit

import planning.collision.sphere_kernel as mut

# ---------------------------------------------------------------------------------------------
# Compile note: ``announce_compile`` says on stderr, once per process, that the kernel is being
# compiled, only when numba's on-disk cache is cold (``cache_is_cold``). No test here waits for
# a real cold compile of the kernel: the predicate is replaced, or tried on a tiny function.
# ---------------------------------------------------------------------------------------------


@pytest.fixture
def fresh_process(monkeypatch):
    """As in a new process: announce_compile has not looked yet (restored afterwards)."""
    monkeypatch.setattr(mut, "_announce_done", False)
    return monkeypatch


def test_note_once_per_process_when_the_cache_is_cold(fresh_process, capsys):
    fresh_process.setattr(mut, "cache_is_cold", lambda dispatcher=None: True)
    assert mut.announce_compile()
    assert not mut.announce_compile()
    out, err = capsys.readouterr()
    assert err == mut.COMPILE_NOTE + "\n" and out == ""
    assert "compiling the collision kernel" in mut.COMPILE_NOTE


def test_no_note_when_the_cache_is_warm_and_one_look_only(fresh_process, capsys):
    looks = []
    fresh_process.setattr(mut, "cache_is_cold", lambda dispatcher=None: looks.append(1) or False)
    assert not mut.announce_compile()
    assert not mut.announce_compile()
    assert looks == [1]
    assert capsys.readouterr() == ("", "")


def test_a_sphere_model_announces_before_its_first_kernel_call(fresh_process, capsys):
    from planning import PlanningScene
    from planning.collision.spheres import SphereCollisionModel

    fresh_process.setattr(mut, "cache_is_cold", lambda dispatcher=None: True)
    model = SphereCollisionModel(PlanningScene(), 0.015)  # warms the kernel up: classify
    model.classify([[0.0] * 7])
    assert capsys.readouterr().err.count(mut.COMPILE_NOTE) == 1


def _load_module(path):
    """Imports ``path`` under a new name: a new dispatcher reading the cache, as a new process."""
    spec = importlib.util.spec_from_file_location(f"tiny_{uuid.uuid4().hex}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_cache_is_cold_follows_numbas_on_disk_cache(tmp_path, monkeypatch):
    monkeypatch.setattr(numba.core.config, "CACHE_DIR", "")  # the cache beside the source
    source = tmp_path / "tiny_kernel.py"
    source.write_text(
        "from numba import njit\n\n\n@njit(cache=True)\ndef add(a, b):\n    return a + b\n"
    )
    first = _load_module(source)
    assert mut.cache_is_cold(first.add)  # nothing cached yet
    assert first.add(1, 2) == 3
    assert sum(first.add.stats.cache_misses.values()) == 1  # it did compile
    assert not mut.cache_is_cold(first.add)  # compiled in this process

    second = _load_module(source)
    assert not mut.cache_is_cold(second.add)  # cached on disk
    assert second.add(1, 2) == 3
    assert sum(second.add.stats.cache_hits.values()) == 1  # it did load

    source.write_text(source.read_text().replace("a + b", "b + a + 0"))  # cache now stale
    assert mut.cache_is_cold(_load_module(source).add)


def test_cache_is_cold_without_a_cache_says_false():
    uncached = numba.njit(lambda a: a)
    assert not mut.cache_is_cold(uncached)  # no on-disk cache to ask: no note
    assert not mut.cache_is_cold(lambda a: a)  # not a dispatcher at all


def test_the_kernel_is_cached_once_loaded():
    from planning import PlanningScene
    from planning.collision.sphere_checker import sphere_model

    sphere_model(PlanningScene())  # compiles or loads prefixes
    assert not mut.cache_is_cold()
    # A new dispatcher of the same function, as in the next process, finds it on disk.
    assert not mut.cache_is_cold(numba.njit(cache=True)(mut.prefixes.py_func))


# ---------------------------------------------------------------------------------------------
# The kernel's verdicts, called directly on the KernelData a SphereCollisionModel packs for a
# scene: the scan of segments (``prefixes``) agrees with classifying every sample on its own, a
# configuration inside an obstacle is COLLIDING, one far from everything FREE, and a non-finite
# configuration is never FREE.
# ---------------------------------------------------------------------------------------------
from pydrake.math import RigidTransform  # noqa: E402

from planning import PlanningScene  # noqa: E402
from planning.collision.checker import CheckerAdapter  # noqa: E402
from planning.collision.sphere_checker import sphere_model  # noqa: E402


@pytest.fixture(scope="module")
def scene():
    """The table and a wall in front of the robot."""
    scene = PlanningScene()
    scene.add_box("wall", [0.05, 0.8, 0.8], RigidTransform([0.45, 0.0, 0.4]))
    return scene


def kernel_data(scene) -> mut.KernelData:
    """The arrays the scene's sphere model hands to the kernel, for the scene as it is now."""
    model = sphere_model(scene)
    model.sync()
    return model._data


def classify_each(qs, d):
    """FREE, COLLIDING or UNKNOWN of each configuration alone: a segment of one sample, scanned
    to the end (``stop_at_unknown`` off, so a later certain collision is still found)."""
    qs = np.ascontiguousarray(qs, dtype=float)
    first, n, edge, _ = mut.prefixes(qs, qs, 1.0, False, d)
    assert np.all(n == 1)
    state = np.where(first == 0, mut.COLLIDING, mut.FREE)
    state[edge] = mut.UNKNOWN
    return state


def random_q(scene, n, seed):
    adapter = CheckerAdapter(scene)
    return np.random.default_rng(seed).uniform(adapter.lower, adapter.upper, (n, 7))


def test_the_scan_of_segments_agrees_with_classifying_each_sample(scene):
    """``prefixes`` stops each segment at its first COLLIDING sample (or its first uncertain
    one with stop_at_unknown) and lists the UNKNOWN samples before it."""
    d = kernel_data(scene)
    qs = random_q(scene, 60, seed=6)
    q_a, q_b, step = qs[:30], qs[30:], 0.1
    kinds = set()
    for stop_at_unknown in (False, True):
        first, n, edge, local = mut.prefixes(q_a, q_b, step, stop_at_unknown, d)
        np.testing.assert_array_equal(n, np.ceil(np.linalg.norm(q_b - q_a, axis=1) / step))
        assert np.all(np.diff(edge) >= 0)  # by segment, then in order along it
        for k in range(len(q_a)):
            t = np.arange(1, n[k] + 1) / n[k]
            state = classify_each(q_a[k] + t[:, None] * (q_b[k] - q_a[k]), d)
            kinds |= set(state.tolist())
            blocking = (state != mut.FREE) if stop_at_unknown else (state == mut.COLLIDING)
            expected = int(np.argmax(blocking)) if blocking.any() else n[k]
            assert first[k] == expected
            unknown = np.flatnonzero(state[:expected] == mut.UNKNOWN)
            np.testing.assert_array_equal(local[edge == k], unknown)
    assert kinds == {mut.FREE, mut.COLLIDING, mut.UNKNOWN}  # every verdict was met


def test_verdicts_agree_with_drakes_checker(scene):
    """FREE only where Drake finds no collision, COLLIDING only where it finds one."""
    d = kernel_data(scene)
    qs = random_q(scene, 300, seed=7)
    state = classify_each(qs, d)
    full = np.tile(scene.full_q(np.zeros(7)), (len(qs), 1))
    full[:, scene.model.arm_indices] = qs
    free = np.array([scene.checker.CheckConfigCollisionFree(q) for q in full])
    assert not np.any((state == mut.FREE) & ~free)
    assert not np.any((state == mut.COLLIDING) & free)
    assert np.mean(state != mut.UNKNOWN) > 0.8


def test_inside_an_obstacle_is_colliding_and_far_from_everything_is_free(scene):
    ready = scene.model.named_configurations["ready"]
    p_hand = scene.attachment_pose(ready).translation()
    assert classify_each(ready[None], kernel_data(scene))[0] == mut.FREE
    scene.add_box("far", [0.2, 0.2, 0.2], RigidTransform(p_hand + [0.0, 0.0, 1.5]))
    try:
        assert classify_each(ready[None], kernel_data(scene))[0] == mut.FREE
    finally:
        scene.remove_object("far")
    scene.add_box("block", [0.3, 0.3, 0.3], RigidTransform(p_hand))  # the hand inside it
    try:
        d = kernel_data(scene)
        assert classify_each(ready[None], d)[0] == mut.COLLIDING
        for stop_at_unknown in (False, True):
            first, n, edge, _ = mut.prefixes(ready[None], ready[None], 0.1, stop_at_unknown, d)
            assert first[0] == 0 and n[0] == 1 and len(edge) == 0
    finally:
        scene.remove_object("block")
    assert classify_each(ready[None], kernel_data(scene))[0] == mut.FREE


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_a_non_finite_configuration_is_never_free(scene, bad):
    d = kernel_data(scene)
    ready = scene.model.named_configurations["ready"]
    qs = np.tile(ready, (7, 1))
    qs[np.arange(7), np.arange(7)] = bad  # each joint in turn
    assert np.all(classify_each(qs, d) == mut.UNKNOWN)
    # A segment to a non-finite end has one sample, its end, which is not free.
    starts = np.tile(ready, (7, 1))
    first, n, edge, local = mut.prefixes(starts, qs, 0.1, True, d)
    assert np.all(n == 1) and np.all(first == 0)
    first, n, edge, local = mut.prefixes(starts, qs, 0.1, False, d)
    assert np.all(first == 1)  # not certainly colliding either: left to Drake
    np.testing.assert_array_equal(edge, np.arange(7))
    np.testing.assert_array_equal(local, 0)


# ---------------------------------------------------------------------------------------------
# Certificates: a FREE configuration's radius is how far it may move along a direction with
# every sphere staying FREE; it rests on the speed table's bound on how fast points move.
# ---------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def cluttered():
    """The pick-and-place scene's table and a box near the hand at "ready"."""
    import numpy as np
    from pydrake.math import RigidTransform

    from planning import PlanningScene
    from planning.collision.sphere_checker import sphere_model

    scene = PlanningScene()
    ready = scene.model.named_configurations["ready"]
    p = scene.attachment_pose(ready).translation() + np.array([0.15, 0.0, 0.0])
    scene.add_box("box", [0.1, 0.1, 0.3], RigidTransform(p))
    model = sphere_model(scene)
    return scene, model, model.kernel_data()


def test_points_move_no_faster_than_the_speed_table_says(cluttered):
    scene, model, d = cluttered
    adapter = CheckerAdapter(scene)
    lower, upper = adapter.lower, adapter.upper
    rng = np.random.default_rng(0)
    h = 1e-6
    for q in rng.uniform(lower, upper, (200, 7)):
        p0, _ = model.sphere_centres(q[None])
        for j in range(7):
            p1, _ = model.sphere_centres((q + h * np.eye(7)[j])[None])
            speed = np.linalg.norm(p1[0] - p0[0], axis=1) / h  # (S,) m/rad
            bound = d.speed[model.sphere_bodies, j]
            assert np.all(speed <= bound * (1 + 1e-6) + 1e-9)


@njit
def _radius(q, q_to, d):
    """(verdict, radius) of q for motion towards q_to, with fresh scratch arrays. (The scratch
    tuple itself does not box back into Python from a cached kernel, hence the wrapper.)"""
    lam = np.zeros(len(d.body_step) + len(d.body_pair))
    mut.edge_speeds(q, q_to, d, lam)
    return mut._classify_one(q, d, False, mut._work(d), lam)


def test_a_free_configuration_stays_free_within_its_radius(cluttered):
    scene, model, d = cluttered
    adapter = CheckerAdapter(scene)
    lower, upper = adapter.lower, adapter.upper
    rng = np.random.default_rng(1)
    radii = []
    for q in rng.uniform(lower, upper, (400, 7)):
        u = rng.normal(size=7)
        u /= np.linalg.norm(u)
        state, radius = _radius(q, q + u, d)
        if state != mut.FREE:
            assert radius == 0.0
            continue
        radii.append(radius)
        for f in (-1.0, -0.5, 0.5, 0.999):
            assert _radius(q + f * radius * u, q + u, d)[0] == mut.FREE
    assert len(radii) > 100 and np.median(radii) > 0.002  # certificates that skip samples


def _world_points(d, q, steps, points):
    """The world positions of ``points`` (K, 3), fixed on the kinematic ``steps`` (K,), at the
    arm configuration q."""
    full = d.template.copy()
    full[d.arm] = q
    T = mut.transforms(full[None], d.parent, d.kind, d.q_index, d.terms)[0]  # (J, 3, 4)
    return np.einsum("kij,kj->ki", T[steps, :, :3], points) + T[steps, :, 3]


def test_a_group_far_from_the_other_bodys_sphere_is_far_from_its_groups(cluttered):
    """The self-collision culling the kernels use: a pair's first group out of
    ``pair_side_reach2`` of the other body's centre is out of ``pair_reach2`` of every group of
    that body it is paired with, so skipping those pairs skips no test that could fail."""
    scene, model, d = cluttered
    adapter = CheckerAdapter(scene)
    rng = np.random.default_rng(3)
    runs = d.body_pair_start
    for p in range(len(d.body_pair)):  # each body pair's rows run by their first group
        g = d.pair_group[runs[p] : runs[p + 1], 0]
        assert len(set(g.tolist())) == 1 + np.count_nonzero(np.diff(g))
    culled = 0
    for q in rng.uniform(adapter.lower, adapter.upper, (300, 7)):
        groups = _world_points(d, q, d.group_step, d.p_BG)
        bodies = _world_points(d, q, d.body_step, d.p_BL)
        for p in range(len(d.body_pair)):
            rows = np.arange(runs[p], runs[p + 1])
            g, h = d.pair_group[rows, 0], d.pair_group[rows, 1]
            side2 = np.sum((groups[g] - bodies[d.body_pair[p, 1]]) ** 2, axis=1)
            pair2 = np.sum((groups[g] - groups[h]) ** 2, axis=1)
            far = side2 >= d.pair_side_reach2[rows]
            assert np.all(pair2[far] >= d.pair_reach2[rows][far])
            culled += np.count_nonzero(
                far
                & (
                    np.sum((bodies[d.body_pair[p, 0]] - bodies[d.body_pair[p, 1]]) ** 2)
                    < d.body_pair_reach2[p]
                )
            )
    assert culled > 100  # the culling applies where the bodies' spheres overlap


def test_an_unknown_of_the_robots_own_pairs_alone_says_so(cluttered):
    """With ``stop_at_unknown``, an UNKNOWN whose spheres were all proven FREE of the objects
    (only a pair of the robot's own links undecided) has the radius ``SELF_UNKNOWN``; one
    undecided against an object has 0. Without objects every UNKNOWN is of the first kind."""
    from planning import PlanningConfig, PlanningScene
    from planning.collision.sphere_checker import sphere_model

    scene, model, d = cluttered
    bare = sphere_model(PlanningScene(PlanningConfig(table=None))).kernel_data()
    adapter = CheckerAdapter(scene)
    rng = np.random.default_rng(4)
    kinds = {"bare": set(), "cluttered": set()}
    for q in rng.uniform(adapter.lower, adapter.upper, (600, 7)):
        for name, data in (("bare", bare), ("cluttered", d)):
            state, radius = classify_stopping(q, data)
            if state == mut.UNKNOWN:
                kinds[name].add(radius)
    assert kinds["bare"] == {mut.SELF_UNKNOWN}
    assert kinds["cluttered"] == {mut.SELF_UNKNOWN, 0.0}


@njit
def classify_stopping(q, d):
    """``_classify_one`` with ``stop_at_unknown``, fresh scratch arrays."""
    lam = np.zeros(len(d.body_step) + len(d.body_pair))
    return mut._classify_one(q, d, True, mut._work(d), lam)


class _FakeDispatcher:
    """Stands in for a numba dispatcher with a cache: counts flushes."""

    def __init__(self, module):
        self.flushes = 0
        self._cache = self
        self.py_func = types.SimpleNamespace(__module__=module)  # where it is defined

    def flush(self):
        self.flushes += 1


def test_a_changed_kernel_source_empties_the_cache(tmp_path, monkeypatch):
    source = tmp_path / "planner.py"
    source.write_text("one")
    dispatcher = _FakeDispatcher("planner")
    other = _FakeDispatcher("kernel")  # imported from another module: its cache is that module's
    module = types.SimpleNamespace(
        __file__=str(source), __name__="planner", plan=dispatcher, kernel_function=other
    )
    cache = tmp_path / "cache"
    cache.mkdir()
    mut.refresh_cache(module, [source], cache)  # no hash yet: emptied, hash written
    mut.refresh_cache(module, [source], cache)  # same sources: kept
    assert dispatcher.flushes == 1
    source.write_text("two")  # (the kernel's source is hashed with it the same way)
    mut.refresh_cache(module, [source], cache)
    assert dispatcher.flushes == 2 and other.flushes == 0
    source.write_text("three")

    def read_only(*args, **kwargs):
        raise PermissionError("read-only")

    monkeypatch.setattr(mut.Path, "write_text", read_only)  # the functions are not cached at all
    mut.refresh_cache(module, [source], cache)
    assert isinstance(dispatcher._cache, mut.NullCache)


def test_packed_data_unpacks_to_the_same_arrays_in_compiled_code(scene):
    """``pack`` puts the 35 arrays in two buffers (one typed and unboxed argument each) and
    ``unpack`` gives them back, views of the same values, shapes and types, the sizes of an
    empty world's objects (0 rows) included."""

    @njit
    def roundtrip(floats, ints):
        return mut.unpack(floats, ints)

    empty = PlanningScene()
    for name in list(empty.world_objects):
        empty.remove_object(name)
    for scene_ in (scene, empty):
        data = kernel_data(scene_)
        floats, ints = mut.pack(data)
        assert floats.dtype == np.float64 and ints.dtype == np.int64
        back = roundtrip(floats, ints)
        for name, a, b in zip(mut.KernelData._fields, data, back, strict=True):
            assert a.dtype == b.dtype and a.shape == b.shape, name
            np.testing.assert_array_equal(a, b, err_msg=name)
    assert len(kernel_data(empty).objects) == 0
    # The packed data classify alike: a compiled scan on the unpacked arrays.
    qs = random_q(scene, 50, seed=11)
    data = kernel_data(scene)

    @njit
    def scan(qs, floats, ints):
        return mut.prefixes(qs, qs, 1.0, False, mut.unpack(floats, ints))[0]

    expected = mut.prefixes(qs, qs, 1.0, False, data)[0]
    np.testing.assert_array_equal(scan(qs, *mut.pack(data)), expected)


# Each module whose compiled functions take in this kernel's code, and the sources its cache is
# keyed on besides its own file (the kernel, then the others it inlines), in its order.
_KERNEL_USERS = {
    "planning.collision.sphere_batch": [
        "planning.collision.trig",
        "planning.collision.lane_geometry",
    ],
    "planning.collision.hull_kernel": ["planning.collision.trig"],
    "planning.search.pose_kernel": ["planning.collision.trig"],
    "planning.search.compiled_rrt": [
        "planning.collision.sphere_batch",
        "planning.collision.lane_geometry",
        "planning.collision.trig",
        "planning.collision.hull_kernel",
    ],
}


@pytest.mark.parametrize("name", sorted(_KERNEL_USERS))
def test_modules_compiling_the_kernel_in_key_their_cache_on_it(name):
    """Numba keys a cached function on its own file alone; a module whose compiled functions
    take in this kernel's code keeps a hash of its own source, the kernel's and the others' it
    inlines beside its cache (``refresh_cache``), so that a change of the kernel alone cannot
    leave stale code reading a changed data layout."""
    import hashlib
    import importlib
    from pathlib import Path

    module = importlib.import_module(name)
    cached = [
        v
        for v in vars(module).values()
        if hasattr(v, "py_func") and v._cache and v.py_func.__module__ == name
    ]
    assert cached
    sources = [module, mut] + [importlib.import_module(m) for m in _KERNEL_USERS[name]]
    digest = hashlib.sha256(b"".join(Path(m.__file__).read_bytes() for m in sources))
    marker = Path(cached[0]._cache._cache_path) / f"{Path(module.__file__).stem}.kernel.sha256"
    assert marker.read_text() == digest.hexdigest()
