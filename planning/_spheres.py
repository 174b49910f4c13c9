"""Fast collision checks of many Panda configurations with sphere models, in numpy.

The robot's collision geometry (arm links, hand, fingers at the scene's finger positions, and
held objects) is covered by spheres (``_sphere_robot``); world objects stay exact boxes,
cylinders and spheres. ``SphereCollisionModel.classify`` runs batched forward kinematics
(``_sphere_fk``) for N configurations, then exact point-to-primitive distances (and sphere pair
distances for self-collision) and sorts each configuration into:

- ``FREE``: no outer sphere is within its pair's padding of anything. The outer spheres
  contain the robot's geometry, so Drake's checker finds it collision-free too.
- ``COLLIDING``: two inner balls (each inside the geometry) overlap by more than the pair's
  padding allows, so Drake's checker finds a collision too.
- ``UNKNOWN``: neither; ask Drake.

Which pairs are checked and their paddings are read from the scene's checker: a body pair is
checked when neither the checker's filtered collision matrix (the SRDF's disabled pairs, the
welded base, held-object filters, ``allow_collision``) nor its SceneGraph model filters it, so
they follow the model. Paddings below zero (a held object may touch the world) only loosen the
inner test; the outer test uses at least zero.

Costs: each body's spheres are cut into groups of up to ``_GROUP`` neighbours with a bounding
sphere; a group pass finds the (configuration, group) and (configuration, group pair) cases
with anything near, and only those reach the per-sphere pass. The batched pass runs in single
precision with a margin of ``_MARGIN`` on the safe side. World objects are re-read whenever the
scene's objects change, the robot's spheres whenever held objects or filters change, and the
finger positions on every change.
"""

from __future__ import annotations

import numpy as np
from pydrake.multibody.tree import BodyIndex

from planning._sphere_cover import SphereSet
from planning._sphere_fk import BatchedKinematics
from planning._sphere_robot import cover_shape, robot_spheres
from planning.panda_model import ATTACHMENT_BODY

FREE, COLLIDING, UNKNOWN = 0, 1, 2
_MARGIN = 1e-5  # m, added on the safe side of every comparison (covers float32 rounding)
_FLOAT = np.float32  # the batched pass runs in single precision: half the memory traffic
_CHUNK = 256  # configurations per numpy pass
_GROUP = 4  # spheres per culling group


class SphereCollisionModel:
    """Sphere-based three-way collision classification on a ``PlanningScene``.

    Args:
        scene: the planning scene.
        slack: the sphere cover's slack, m (see ``_sphere_cover.cover_polytope``).

    Attributes:
        supported: False when some geometry has no sphere model or exact formula; then
            ``classify`` answers UNKNOWN everywhere.
    """

    def __init__(self, scene, slack: float = 0.015):
        self._scene, self._slack = scene, slack
        plant, checker = scene.plant, scene.checker
        self._world = int(plant.world_body().index())
        self._filtered = checker.GetFilteredCollisionMatrix()
        self._padding = checker.GetPaddingMatrix()
        self._attachment = int(plant.GetBodyByName(ATTACHMENT_BODY, scene.model.instance).index())
        self._held_cache: dict[tuple, SphereSet] = {}
        self._signature = self._held_signature = self._version = None
        self.supported = True
        try:
            query = checker.MakeStandaloneModelContext().GetQueryObject()
            bodies = [
                int(b)
                for b in plant.GetBodyIndices(scene.model.instance)
                if plant.GetCollisionGeometriesForBody(plant.get_body(b))
            ]
            self._robot = robot_spheres(plant, query.inspector(), bodies, slack)
            self._bodies = [*self._robot, self._attachment]
            self._kin = BatchedKinematics(plant, self._bodies)
        except NotImplementedError:
            self.supported = False
        self.sync()

    # ---------------------------------------------------------------------------- scene ----
    def sync(self) -> None:
        """Re-reads world objects, held objects and finger positions when they changed."""
        scene = self._scene
        version = getattr(scene, "version", None)  # PlanningScene bumps it on every change
        if version is not None and version == self._version:
            return
        self._version = version
        world, held = scene.world_objects, scene.attached_objects
        filtered = scene.checker.GetFilteredCollisionMatrix()
        signature = (
            tuple((n, id(o)) for n, o in world.items()),
            (tuple((n, id(o)) for n, o in held.items()), filtered.tobytes()),
            tuple(scene.finger_positions),
        )
        if signature == self._signature:
            return
        self._signature = signature
        self._template = scene.full_q(np.zeros(7))
        self._arm = scene.model.arm_indices
        self._objects_ok = all(o.shape in ("box", "cylinder", "sphere") for o in world.values())
        self._objects_ok &= all(o.shape in ("box", "cylinder", "sphere") for o in held.values())
        if self.supported and self._objects_ok:
            if signature[1] != self._held_signature:  # held objects or allowed pairs changed
                self._filtered = filtered
                self._build_robot(held)
                self._held_signature = signature[1]
            self._objects = _Primitives(world.values())

    def _build_robot(self, held) -> None:
        sets = dict(self._robot)
        held_sets = [self._held(obj) for obj in held.values()]
        if held_sets:
            sets[self._attachment] = SphereSet.concat(held_sets)
        slot = {b: k for k, b in enumerate(self._bodies)}
        present = list(sets)
        owner = np.concatenate([np.full(len(sets[b].radius), b) for b in present])
        self._slot = np.array([slot[b] for b in owner], dtype=int)
        p_BS = np.vstack([sets[b].p_BS for b in present])
        self._p_BS = np.vstack([p_BS.T, np.ones(len(owner))])  # (4, S), homogeneous
        radius = np.concatenate([sets[b].radius for b in present])
        inner = np.concatenate([sets[b].inner for b in present])
        self._radius = radius
        # Groups of up to _GROUP neighbouring spheres of one body, each with a bounding sphere:
        # configurations are culled per group before spheres are looked at.
        groups = [(b, m) for b in present for m in _groups(np.flatnonzero(owner == b), p_BS)]
        bounds = [_bound(p_BS[m], radius[m]) for _, m in groups]
        self._group_slot = np.array([slot[b] for b, _ in groups], dtype=int)
        self._group_centre = np.vstack([np.array([c for c, _ in bounds]).T, np.ones(len(groups))])
        group_radius = np.array([r for _, r in bounds])
        members = np.zeros((len(groups), _GROUP), dtype=int)
        for g, (_, m) in enumerate(groups):
            members[g, : len(m)] = m
        used = np.arange(_GROUP)[None, :] < np.array([len(m) for _, m in groups])[:, None]
        # Environment: groups of bodies not filtered against the world (not the welded base).
        env = [g for g, (b, _) in enumerate(groups) if self._filtered[b, self._world] == 0]
        pad = np.array([self._padding[groups[g][0], self._world] for g in env]).reshape(-1, 1)
        self._env = np.array(env, dtype=int)
        self._env_members = members[env]
        self._env_reach2 = (group_radius[env] + np.maximum(pad[:, 0], 0.0) + _MARGIN)[:, None] ** 2
        r_out = radius[members[env]] + np.maximum(pad, 0.0) + _MARGIN
        self._env_out = np.where(used[env], _squared(r_out), -1.0)
        r_in = inner[members[env]]
        self._env_in = np.where(used[env] & (r_in > 0), _squared(r_in + pad - _MARGIN), -1.0)
        # Self-collision: group pairs of the body pairs the checker checks, sphere pairs padded
        # to _GROUP**2 per group pair.
        checked_bodies = self._checked_body_pairs(present)
        checked = [
            (g, h)
            for g, (a, _) in enumerate(groups)
            for h, (b, _) in enumerate(groups)
            if (a, b) in checked_bodies
        ]
        n_pairs = _GROUP * _GROUP
        self._group_pairs = np.array(checked, dtype=int).reshape(-1, 2)
        self._pair_a = np.zeros((len(checked), n_pairs), dtype=int)
        self._pair_b = np.zeros((len(checked), n_pairs), dtype=int)
        self._pair_out = np.full((len(checked), n_pairs), -1.0)
        self._pair_in = np.full((len(checked), n_pairs), -1.0)
        reach = np.zeros(len(checked))
        for k, (g, h) in enumerate(checked):
            (a, ma), (b, mb) = groups[g], groups[h]
            pad = self._padding[a, b]
            reach[k] = group_radius[g] + group_radius[h] + max(pad, 0.0) + _MARGIN
            ia, ib = np.repeat(ma, len(mb)), np.tile(mb, len(ma))
            count = len(ia)
            self._pair_a[k, :count], self._pair_b[k, :count] = ia, ib
            self._pair_out[k, :count] = _squared(radius[ia] + radius[ib] + max(pad, 0) + _MARGIN)
            ok = (inner[ia] > 0) & (inner[ib] > 0)
            r_in = np.where(ok, inner[ia] + inner[ib] + pad - _MARGIN, -1.0)
            self._pair_in[k, :count] = _squared(r_in)
        self._group_reach2 = (reach**2)[:, None]
        for name in (
            "_p_BS",
            "_group_centre",
            "_env_reach2",
            "_env_out",
            "_env_in",
            "_pair_out",
            "_pair_in",
            "_group_reach2",
        ):
            setattr(self, name, getattr(self, name).astype(_FLOAT))

    def _checked_body_pairs(self, present: list[int]) -> set[tuple[int, int]]:
        """Body pairs (a before b in ``present``) that Drake's checker checks: filtered
        neither by the checker nor in its SceneGraph model (the checker's queries honour
        both)."""
        plant = self._scene.plant
        inspector = self._scene.checker.MakeStandaloneModelContext().GetQueryObject().inspector()
        geometries = {
            b: plant.GetCollisionGeometriesForBody(plant.get_body(BodyIndex(b))) for b in present
        }
        pairs = set()
        for i, a in enumerate(present):
            for b in present[i + 1 :]:
                if self._filtered[a, b] != 0:
                    continue
                if any(
                    not inspector.CollisionFiltered(g, h)
                    for g in geometries[a]
                    for h in geometries[b]
                ):
                    pairs.add((a, b))
        return pairs

    def _held(self, obj) -> SphereSet:
        key = (obj.shape, obj.size)
        if key not in self._held_cache:
            from pydrake.math import RigidTransform

            shape = obj.drake_shape()
            self._held_cache[key] = cover_shape(shape, RigidTransform(), self._slack, scaled=True)
        cover = self._held_cache[key]
        return cover.transformed(obj.X_PO.rotation().matrix(), obj.X_PO.translation())

    @property
    def active(self) -> bool:
        """True when ``classify`` can answer (all geometry has spheres or exact formulas)."""
        self.sync()
        return self.supported and self._objects_ok

    @property
    def num_spheres(self) -> int:
        return len(self._radius)

    # -------------------------------------------------------------------------- queries ----
    def sphere_centres(self, qs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Returns the spheres' centres p_WS (N, S, 3) for configurations qs (N, 7) and their
        outer radii (S,), m."""
        self.sync()
        T = self._transforms(np.atleast_2d(qs))
        return _apply(T, self._slot, self._p_BS).transpose(2, 1, 0), self._radius.copy()

    def _transforms(self, qs: np.ndarray) -> np.ndarray:
        full = np.tile(self._template, (len(qs), 1))
        full[:, self._arm] = qs
        return self._kin.transforms(full)

    def classify(self, qs) -> np.ndarray:
        """Returns FREE, COLLIDING or UNKNOWN (int8 array) for each row of qs (N, 7), rad."""
        qs = np.atleast_2d(np.asarray(qs, dtype=float))
        out = np.full(len(qs), UNKNOWN, dtype=np.int8)
        if not self.active:
            return out
        for start in range(0, len(qs), _CHUNK):
            out[start : start + _CHUNK] = self._classify(qs[start : start + _CHUNK])
        return out

    def _classify(self, qs: np.ndarray) -> np.ndarray:
        n = len(qs)
        T = self._transforms(qs).astype(_FLOAT)
        centres = _apply(T, self._slot, self._p_BS)  # (3, S, N)
        groups = _apply(T, self._group_slot, self._group_centre)  # (3, G, N)
        outer = np.zeros(n, dtype=bool)
        inner = np.zeros(n, dtype=bool)
        if self._objects.count and len(self._env):
            d2 = self._objects.min_distance2(groups[:, self._env].reshape(3, -1))
            g, r = np.nonzero(d2.reshape(len(self._env), n) < self._env_reach2)
            if len(g):
                points = centres[:, self._env_members[g], r[:, None]]  # (3, M, _GROUP)
                d2 = self._objects.min_distance2(points.reshape(3, -1))
                d2 = d2.reshape(len(g), _GROUP)
                outer[r[(d2 < self._env_out[g]).any(axis=1)]] = True
                inner[r[(d2 < self._env_in[g]).any(axis=1)]] = True
        if len(self._group_pairs):
            diff = groups[:, self._group_pairs[:, 0]] - groups[:, self._group_pairs[:, 1]]
            k, r = np.nonzero((diff * diff).sum(axis=0) < self._group_reach2)  # near group pairs
            if len(k):
                rows = r[:, None]
                diff = centres[:, self._pair_a[k], rows] - centres[:, self._pair_b[k], rows]
                d2 = (diff * diff).sum(axis=0)  # (M, _GROUP**2)
                outer[r[(d2 < self._pair_out[k]).any(axis=1)]] = True
                inner[r[(d2 < self._pair_in[k]).any(axis=1)]] = True
        return np.where(inner, COLLIDING, np.where(outer, UNKNOWN, FREE)).astype(np.int8)


def _apply(T: np.ndarray, slot: np.ndarray, p_B: np.ndarray) -> np.ndarray:
    """Points p_W (3, P, N) of points p_B (4, P, homogeneous) fixed on bodies ``slot`` (P,),
    for body poses T (K, N, 4, 4). (Elementwise on purpose: a matrix product with an inner
    size of 4 is slow, and multi-threaded BLAS is slower still on a loaded machine.)"""
    T3 = np.ascontiguousarray(T[:, :, :3, :].transpose(2, 3, 0, 1))  # (3, 4, K, N)
    G = np.take(T3, slot, axis=2)  # (3, 4, P, N)
    out = G[:, 3].copy()
    for i in range(3):
        out += G[:, i] * p_B[i][:, None]
    return out


def _squared(reach: np.ndarray) -> np.ndarray:
    """reach**2 where reach > 0, else -1 (never above a squared distance)."""
    return np.where(reach > 0, reach * reach, -1.0)


def _bound(centres: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, float]:
    """A sphere containing spheres (centres (P, 3), radii (P,)): its centre and radius, m."""
    centre = centres.mean(axis=0)
    return centre, float((np.linalg.norm(centres - centre, axis=1) + radii).max())


def _groups(members: np.ndarray, p: np.ndarray, size: int = _GROUP) -> list[np.ndarray]:
    """Splits sphere indices into groups of at most ``size`` neighbours: sorted along the
    direction in which their centres p[members] spread most, then cut in runs."""
    if len(members) <= size:
        return [members]
    x = p[members] - p[members].mean(axis=0)
    direction = np.linalg.svd(x, full_matrices=False)[2][0]
    ordered = members[np.argsort(x @ direction)]
    return [ordered[k : k + size] for k in range(0, len(ordered), size)]


class _Primitives:
    """World boxes, cylinders and spheres as arrays; ``min_distance2`` gives the squared
    Euclidean distance from points to the nearest object (0 inside), m^2.

    Points are taken into every box and cylinder frame O at once with one matrix product:
    p_OQ = R_WO^T p_WQ - R_WO^T p_WO, the rotations stacked side by side.
    """

    def __init__(self, objects):
        objects = list(objects)
        boxes = [o for o in objects if o.shape == "box"]
        cylinders = [o for o in objects if o.shape == "cylinder"]
        spheres = [o for o in objects if o.shape == "sphere"]
        self.count = len(objects)
        framed = boxes + cylinders
        R = [o.X_PO.rotation().matrix() for o in framed]
        self._W = np.hstack(R) if R else np.zeros((3, 0))  # (3, 3F): [R_WO1 R_WO2 ...]
        offsets = [r.T @ o.X_PO.translation() for r, o in zip(R, framed, strict=True)]
        self._offset = np.concatenate(offsets) if offsets else np.zeros(0)
        self._nb = len(boxes)
        self._box_h = np.array([o.size for o in boxes]).reshape(-1, 3) / 2
        self._cyl_r = np.array([o.size[0] for o in cylinders])
        self._cyl_h = np.array([o.size[1] / 2 for o in cylinders])
        self._sph_p = np.array([o.X_PO.translation() for o in spheres]).reshape(-1, 3)
        self._sph_r = np.array([o.size[0] for o in spheres])
        for name in ("_W", "_offset", "_box_h", "_cyl_r", "_cyl_h", "_sph_p", "_sph_r"):
            setattr(self, name, getattr(self, name).astype(_FLOAT))

    def min_distance2(self, points: np.ndarray) -> np.ndarray:
        """Squared distances (M,) from points (3, M) to the nearest object, m^2 (in place
        wherever possible: the cost is memory traffic)."""
        best = None
        if self._W.shape[1]:
            local = self._W.T @ points
            local -= self._offset[:, None]
            local = local.reshape(-1, 3, points.shape[1])
            if self._nb:
                box = local[: self._nb]
                np.abs(box, out=box)
                box -= self._box_h[:, :, None]
                np.maximum(box, 0.0, out=box)
                np.square(box, out=box)
                best = box.sum(axis=1).min(axis=0)
            cyl = local[self._nb :]
            if len(cyl):
                radial = np.square(cyl[:, 0])
                radial += np.square(cyl[:, 1])
                np.sqrt(radial, out=radial)
                radial -= self._cyl_r[:, None]
                np.maximum(radial, 0.0, out=radial)
                np.square(radial, out=radial)
                axial = np.abs(cyl[:, 2])
                axial -= self._cyl_h[:, None]
                np.maximum(axial, 0.0, out=axial)
                np.square(axial, out=axial)
                radial += axial
                d = radial.min(axis=0)
                best = d if best is None else np.minimum(best, d, out=best)
        if len(self._sph_p):
            diff = points[None, :, :] - self._sph_p[:, :, None]
            d = np.maximum(np.sqrt((diff * diff).sum(axis=1)) - self._sph_r[:, None], 0.0)
            d = np.square(d).min(axis=0)
            best = d if best is None else np.minimum(best, d, out=best)
        return best
