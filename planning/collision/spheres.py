"""Fast collision checks of many Panda configurations with sphere models.

The robot's collision geometry (arm links, hand, fingers at the scene's finger positions, and
held objects) is covered by spheres (``sphere_robot``); world objects stay exact boxes,
cylinders and spheres. ``SphereCollisionModel.classify`` runs forward kinematics for each
configuration, then exact point-to-primitive distances (and sphere pair distances for
self-collision), in compiled loops (``sphere_kernel``), and sorts each configuration into:

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
sphere; only groups (and group pairs) with anything near reach the per-sphere pass, and a
configuration stops at its first certain collision. Every comparison has a margin of
``_MARGIN`` on the safe side. World objects are re-read whenever the
scene's objects change, the robot's spheres whenever held objects or filters change, and the
robot's part of the kernel data (its folded kinematics, speed bounds) when those or the finger
positions change.
"""

from __future__ import annotations

import numpy as np
from pydrake.multibody.tree import BodyIndex

from planning.collision import sphere_kernel as _kernel
from planning.collision.hull_kernel import MARGIN as _HULL_MARGIN
from planning.collision.hull_kernel import HullData, prove_free_packed
from planning.collision.sphere_batch import classify_many
from planning.collision.sphere_cover import SphereSet
from planning.collision.sphere_fk import BatchedKinematics, fold_fixed_steps, fold_points
from planning.collision.sphere_kernel import COLLIDING, FREE, UNKNOWN, KernelData
from planning.collision.sphere_robot import held_cover, robot_hulls, robot_spheres, shape_hull
from planning.model.layout import NUM_ARM_JOINTS
from planning.model.panda import ATTACHMENT_BODY

__all__ = ["COLLIDING", "FREE", "UNKNOWN", "SphereCollisionModel"]
_MARGIN = 1e-5  # m, added on the safe side of every comparison (covers rounding)
_GROUP = 4  # spheres per culling group
# (step, point) arrays of the kernel data whose points are fixed on kinematic steps.
_FOLDED = (("sphere_step", "p_BS"), ("group_step", "p_BG"), ("body_step", "p_BL"))
# KernelData's square roots of squared thresholds, by name (for the certificates' clearances).
_ROOTS = {
    "env_reach": "env_reach2",
    "env_out_root": "env_out",
    "body_pair_reach": "body_pair_reach2",
    "pair_reach": "pair_reach2",
    "pair_out_root": "pair_out",
    "pair_side_reach": "pair_side_reach2",
}


class SphereCollisionModel:
    """Sphere-based three-way collision classification on a ``PlanningScene``.

    Args:
        scene: the planning scene.
        slack: the sphere cover's slack, m (see ``sphere_cover.cover_polytope``).

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
        self._groups_cache: dict[int, tuple] = {}  # body -> _body_groups
        self._signature = self._held_signature = self._robot_signature = self._version = None
        self._packed = {}  # "kernel" or "hulls" -> (the data, its packed buffers)
        self._alive = {}  # signature name -> the objects it names (see ``sync``)
        self._stale_version = None  # the scene's version whose robot part sync left undone
        self.supported = True
        try:
            query = checker.MakeStandaloneModelContext().GetQueryObject()
            bodies = [
                int(b)
                for b in plant.GetBodyIndices(scene.model.instance)
                if plant.GetCollisionGeometriesForBody(plant.get_body(b))
            ]
            self._robot = robot_spheres(plant, query.inspector(), bodies, slack)
            self._hulls = robot_hulls(plant, query.inspector(), bodies)
            self._bodies = [*self._robot, self._attachment]
            self._unfiltered = _unfiltered_in_model(plant, query.inspector(), self._bodies)
            self._kin = BatchedKinematics(plant, self._bodies)
        except NotImplementedError:
            self.supported = False
        self.sync()
        # Compiles or loads the kernels now, not mid-request.
        self.classify(np.zeros((1, NUM_ARM_JOINTS)))
        self.prefixes(np.zeros((1, NUM_ARM_JOINTS)), np.zeros((1, NUM_ARM_JOINTS)), 1.0, False)

    # ---------------------------------------------------------------------------- scene ----
    def sync(self, *, rebuild_robot: bool = True) -> bool:
        """Re-reads world objects, held objects and finger positions when they changed.

        Args:
            rebuild_robot: False: leave the model as it is (out of sync) when the robot's part
                (held objects, allowed pairs, fingers) changed, whose arrays take long to make
                for a tight cover (~45 ms for 1163 spheres, against ~0.5 ms for 189).

        Returns:
            True when the model is in sync with the scene.
        """
        scene = self._scene
        version = getattr(scene, "version", None)  # PlanningScene bumps it on every change
        if version is not None and version == self._version:
            return True
        if not rebuild_robot and version is not None and version == self._stale_version:
            return False
        world, held = scene.world_objects, scene.attached_objects
        filtered = scene.checker.GetFilteredCollisionMatrix()
        # Objects by identity; each signature kept holds on to its objects too (``_alive``), so
        # that no new object can take the id of one it names (say, an object removed and a new
        # one attached under its name between two syncs).
        signature = (
            tuple((n, id(o)) for n, o in world.items()),
            (tuple((n, id(o)) for n, o in held.items()), filtered.tobytes()),
            tuple(scene.finger_positions),
        )
        objects = (tuple(world.values()), tuple(held.values()))
        if not rebuild_robot and signature[1:] != self._robot_signature:
            self._stale_version = version  # the robot's part is out of date at this version
            return False
        self._version = version
        if signature == self._signature:
            return True
        self._signature = signature
        self._alive["all"] = objects
        self._template = scene.full_q(np.zeros(NUM_ARM_JOINTS))
        self._arm = scene.model.arm_indices
        self._objects_ok = all(o.shape in ("box", "cylinder", "sphere") for o in world.values())
        self._objects_ok &= all(o.shape in ("box", "cylinder", "sphere") for o in held.values())
        if self.supported and self._objects_ok:
            if signature[1] != self._held_signature:  # held objects or allowed pairs changed
                self._filtered = filtered
                self._build_robot(held)
                self._held_signature = signature[1]
                self._alive["held"] = objects[1]
            if signature[1:] != self._robot_signature:  # the robot's part: held objects, fingers
                self._robot_data = self._robot_kernel_arrays()
                self._robot_signature = signature[1:]
                self._alive["robot"] = objects[1]
            self._data = KernelData(**self._robot_data, objects=_primitives(world.values()))
        return True

    def _robot_kernel_arrays(self) -> dict:
        """The ``KernelData`` fields other than ``objects`` (they depend on the robot, its held
        objects and the finger positions alone, not on the world's objects)."""
        template = np.ascontiguousarray(self._template, dtype=float)
        arm = np.asarray(self._arm, dtype=np.int64)
        # The kernels run the tree with its fixed steps folded away (the fingers too, at the
        # template's positions): the points those steps carried move into the frames of the
        # steps that carry them now, at most their offset's translation farther from those
        # frames' origins (which the speed bounds take in).
        tree, offsets = fold_fixed_steps(*self._kin.arrays(), template, arm)
        arrays = dict(self._robot_arrays)
        shift = np.array([np.linalg.norm(X[:3, 3]) for _, X in offsets])
        point_norm = self._point_norm + shift[arrays["body_step"]]
        for steps, points in _FOLDED:
            arrays[steps], arrays[points] = fold_points(offsets, arrays[steps], arrays[points])
        self._hull_data = self._folded_hulls(offsets)
        parent, kind, q_index, terms = tree
        return dict(
            parent=parent,
            kind=kind,
            q_index=q_index,
            terms=terms,
            template=template,
            arm=arm,
            **arrays,
            speed=speed_table(*tree, template, arm, arrays["body_step"], point_norm),
            **{name: np.sqrt(np.maximum(arrays[squared], 0.0)) for name, squared in _ROOTS.items()},
        )

    def _folded_hulls(self, offsets) -> HullData:
        """``HullData`` of the shapes ``_build_robot`` listed, on the folded tree's steps."""
        raw = self._hull_raw
        counts = np.diff(raw["vert_start"])
        _, vert = fold_points(offsets, np.repeat(raw["geom_step"], counts), raw["vert"])
        geom_step, centre = fold_points(offsets, raw["geom_step"], raw["geom_centre"])
        fields = dict(raw, geom_step=geom_step, vert=vert, geom_centre=centre)
        return HullData(**{k: np.ascontiguousarray(v) for k, v in fields.items()})

    def _build_hulls(self, present, held, step, slot) -> None:
        """Lists the robot's collision shapes (held objects included) for ``HullData``: each
        shape's step, vertices, swept radius and bounding sphere, its clearance to prove to the
        world (-1: filtered), and the shape pairs of the body pairs the checker checks."""
        shapes = {b: list(self._hulls.get(b, [])) for b in present}
        if held:
            shapes[self._attachment] = [shape_hull(o.drake_shape(), o.X_PO) for o in held.values()]
        geom_step, verts, radius, centre, bound, world, owner = [], [], [], [], [], [], []
        for b in present:
            for v, r in shapes[b]:
                c = v.mean(axis=0)
                geom_step.append(step[slot[b]])
                verts.append(v)
                radius.append(r)
                centre.append(c)
                bound.append(float(np.linalg.norm(v - c, axis=1).max()) + r)
                pad = max(self._padding[b, self._world], 0.0) + _HULL_MARGIN
                world.append(pad if self._filtered[b, self._world] == 0 else -1.0)
                owner.append(b)
        owner = np.array(owner, dtype=np.int64)
        pairs, gaps = [], []
        for a, b in sorted(self._checked_body_pairs(present)):
            gap = max(self._padding[a, b], 0.0) + _HULL_MARGIN
            for g in np.flatnonzero(owner == a):
                for e in np.flatnonzero(owner == b):
                    pairs.append((g, e))
                    gaps.append(gap)
        self._hull_raw = dict(
            geom_step=np.array(geom_step, dtype=np.int64),
            vert_start=np.r_[0, np.cumsum([len(v) for v in verts])].astype(np.int64),
            vert=np.vstack(verts) if verts else np.zeros((0, 3)),
            geom_radius=np.array(radius, dtype=float),
            geom_centre=np.array(centre, dtype=float).reshape(-1, 3),
            geom_bound=np.array(bound, dtype=float),
            geom_world=np.array(world, dtype=float),
            pair=np.array(pairs, dtype=np.int64).reshape(-1, 2),
            pair_gap=np.array(gaps, dtype=float),
        )

    def _build_robot(self, held) -> None:
        sets = dict(self._robot)
        held_sets = [self._held(obj) for obj in held.values()]
        if held_sets:
            sets[self._attachment] = SphereSet.concat(held_sets)
        slot = {b: k for k, b in enumerate(self._bodies)}
        present = list(sets)
        counts = [len(sets[b].radius) for b in present]
        self._slot = np.repeat([slot[b] for b in present], counts).astype(int)
        self._sphere_body = np.repeat(np.arange(len(present)), counts).astype(int)
        p_BS = np.vstack([sets[b].p_BS for b in present])
        radius = np.concatenate([sets[b].radius for b in present])
        inner = np.concatenate([sets[b].inner for b in present])
        self._radius = radius
        # Groups of up to _GROUP neighbouring spheres of one body, each with a bounding sphere,
        # and a bounding sphere of each body's groups: configurations are culled per body, then
        # per group, before spheres are looked at.
        groups, bounds, group_body, body_bounds, point_norm = [], [], [], [], []
        offset = 0
        for k, b in enumerate(present):
            local, local_bounds, body_bound, norm = self._body_groups(b, sets[b])
            groups += [(b, m + offset) for m in local]
            bounds += local_bounds
            group_body += [k] * len(local)
            body_bounds.append(body_bound)
            point_norm.append(norm)
            offset += len(sets[b].radius)
        group_centre = np.array([c for c, _ in bounds]).reshape(-1, 3)
        group_radius = np.array([r for _, r in bounds])
        group_body = np.array(group_body, dtype=np.int64)
        step = self._kin.out  # kinematic step of each of self._bodies
        self._build_hulls(present, held, step, slot)
        members = np.zeros((len(groups), _GROUP), dtype=np.int64)
        for g, (_, m) in enumerate(groups):
            members[g, : len(m)] = m
        used = np.arange(_GROUP)[None, :] < np.array([len(m) for _, m in groups])[:, None]
        # Environment: groups of bodies not filtered against the world (not the welded base).
        env = [g for g, (b, _) in enumerate(groups) if self._filtered[b, self._world] == 0]
        world_pad = np.array([self._padding[b, self._world] for b in present])
        pad = world_pad[group_body[env]][:, None]
        r_out = radius[members[env]] + np.maximum(pad, 0.0) + _MARGIN
        r_in = inner[members[env]]
        body_radius = np.array([r for _, r in body_bounds])
        body_centre = np.array([c for c, _ in body_bounds]).reshape(-1, 3)
        self._point_norm = np.array(point_norm)
        arrays = dict(
            sphere_step=step[self._slot],
            p_BS=p_BS,
            body_step=step[[slot[b] for b in present]],
            p_BL=body_centre,
            body_reach=body_radius + np.maximum(world_pad, 0.0) + _MARGIN,
            group_step=step[[slot[b] for b, _ in groups]],
            p_BG=group_centre,
            env_group=np.array(env, dtype=np.int64),
            env_body=group_body[env],
            env_reach2=(group_radius[env] + np.maximum(pad[:, 0], 0.0) + _MARGIN) ** 2,
            env_member=members[env],
            env_out=np.where(used[env], _squared(r_out), -1.0),
            env_in=np.where(used[env] & (r_in > 0), _squared(r_in + pad - _MARGIN), -1.0),
        )
        # Self-collision: group pairs of the body pairs the checker checks, sphere pairs padded
        # to _GROUP**2 per group pair, in runs per body pair.
        checked_bodies = np.zeros((len(present), len(present)), dtype=bool)
        where = {b: k for k, b in enumerate(present)}
        for a, b in self._checked_body_pairs(present):
            checked_bodies[where[a], where[b]] = True
        # Group pairs (g, h) of checked body pairs, sorted by (body of g, body of h, g, h).
        g, h = np.nonzero(checked_bodies[group_body[:, None], group_body[None, :]])
        key = group_body[g] * len(present) + group_body[h]
        order = np.lexsort((h, g, key))
        g, h, key = g[order].astype(np.int64), h[order].astype(np.int64), key[order]
        first = np.flatnonzero(np.r_[True, key[1:] != key[:-1]]) if len(key) else key
        body_pairs = [(int(group_body[g[k]]), int(group_body[h[k]])) for k in first]
        run = np.r_[first, len(key)]
        # Every (sphere of g, sphere of h) of each checked group pair, _GROUP**2 per row.
        shape = (len(g), _GROUP * _GROUP)
        pair_a = np.broadcast_to(members[g][:, :, None], (len(g), _GROUP, _GROUP)).reshape(shape)
        pair_b = np.broadcast_to(members[h][:, None, :], (len(h), _GROUP, _GROUP)).reshape(shape)
        valid = (used[g][:, :, None] & used[h][:, None, :]).reshape(shape)
        owner_of = np.array([b for b, _ in groups], dtype=np.int64)  # body index of each group
        pad = self._padding[owner_of[g], owner_of[h]].reshape(-1, 1)
        reach = group_radius[g] + group_radius[h] + np.maximum(pad[:, 0], 0.0) + _MARGIN
        r_out = radius[pair_a] + radius[pair_b] + np.maximum(pad, 0.0) + _MARGIN
        pair_out = np.where(valid, _squared(r_out), -1.0)
        ok = valid & (inner[pair_a] > 0) & (inner[pair_b] > 0)
        pair_in = np.where(ok, _squared(inner[pair_a] + inner[pair_b] + pad - _MARGIN), -1.0)
        body_pad = np.array(
            [max(self._padding[present[i], present[j]], 0.0) for i, j in body_pairs]
        )
        body_pairs = np.array(body_pairs, dtype=np.int64).reshape(-1, 2)
        arrays.update(
            body_pair=body_pairs,
            body_pair_reach2=(
                body_radius[body_pairs[:, 0]] + body_radius[body_pairs[:, 1]] + body_pad + _MARGIN
            )
            ** 2,
            body_pair_start=np.asarray(run, dtype=np.int64),
            pair_group=np.column_stack((g, h)).astype(np.int64).reshape(-1, 2),
            pair_reach2=reach**2,
            # The first group of each pair against the other body's bounding sphere (which holds
            # every group of that body): out of this reach, none of its pairs with that body is
            # within theirs.
            pair_side_reach2=(
                group_radius[g] + body_radius[group_body[h]] + np.maximum(pad[:, 0], 0.0) + _MARGIN
            )
            ** 2,
            pair_a=pair_a,
            pair_b=pair_b,
            pair_out=pair_out,
            pair_in=pair_in,
        )
        self._robot_arrays = {k: np.ascontiguousarray(v) for k, v in arrays.items()}

    def _body_groups(self, body: int, spheres: SphereSet):
        """(groups of the body's spheres as index arrays into ``spheres``, a bounding sphere
        of each (``_bound``), one of all those groups, and how far from the body's origin any
        point the checks use lies (sphere, group or body centre; for ``speed_table``)): kept
        for the robot's own bodies, whose spheres never change."""
        if body in self._groups_cache and body != self._attachment:
            return self._groups_cache[body]
        local = _groups(np.arange(len(spheres.radius)), spheres.p_BS)
        bounds = [_bound(spheres.p_BS[m], spheres.radius[m]) for m in local]
        centres = np.array([c for c, _ in bounds]).reshape(-1, 3)
        whole = _bound(centres, np.array([r for _, r in bounds]))
        norm = max(
            np.linalg.norm(whole[0]),
            np.linalg.norm(centres, axis=1).max(initial=0.0),
            np.linalg.norm(spheres.p_BS, axis=1).max(initial=0.0),
        )
        out = (local, bounds, whole, norm)
        self._groups_cache[body] = out
        return out

    def _checked_body_pairs(self, present: list[int]) -> set[tuple[int, int]]:
        """Body pairs (a before b in ``present``) that Drake's checker checks: filtered
        neither by the checker nor in its SceneGraph model (the checker's queries honour
        both); a body whose shapes were added to the checker only (a held object) is checked
        against every body the checker does not filter."""
        plant = self._scene.plant
        modelled = {
            b for b in present if plant.GetCollisionGeometriesForBody(plant.get_body(BodyIndex(b)))
        }
        pairs = set()
        for i, a in enumerate(present):
            for b in present[i + 1 :]:
                if self._filtered[a, b] != 0:
                    continue
                # Shapes added to the checker (held objects, on the attachment body) are not in
                # its SceneGraph model: only the checker's own filter applies to them.
                if a not in modelled or b not in modelled or (a, b) in self._unfiltered:
                    pairs.add((a, b))
        return pairs

    def _held(self, obj) -> SphereSet:
        key = (obj.shape, obj.size)
        if key not in self._held_cache:
            self._held_cache[key] = held_cover(obj.drake_shape(), self._slack)
        cover = self._held_cache[key]
        return cover.transformed(obj.X_PO.rotation().matrix(), obj.X_PO.translation())

    @property
    def active(self) -> bool:
        """True when ``classify`` can answer (all geometry has spheres or exact formulas)."""
        self.sync()
        return self.supported and self._objects_ok

    def kernel_data(self) -> KernelData:
        """The arrays the compiled kernels read, in sync with the scene (``active`` only)."""
        self.sync()
        _kernel.announce_compile()
        return self._data

    def packed_data(self) -> tuple[np.ndarray, np.ndarray]:
        """``kernel_data`` in two buffers (``sphere_kernel.pack``), packed once per change."""
        return self._packed_once("kernel", self.kernel_data())

    def _packed_once(self, name: str, data) -> tuple[np.ndarray, np.ndarray]:
        """``sphere_kernel.pack(data)``, remade only when ``data`` is another object than the
        one packed under ``name`` last."""
        packed = self._packed.get(name)
        if packed is None or packed[0] is not data:
            packed = self._packed[name] = (data, _kernel.pack(data))
        return packed[1]

    def hull_data(self) -> HullData:
        """The robot's exact collision shapes (``hull_kernel``), in sync with the scene
        (``active`` only); read with ``kernel_data``'s kinematics and objects."""
        self.sync()
        return self._hull_data

    def packed_hulls(self) -> tuple[np.ndarray, np.ndarray]:
        """``hull_data`` in two buffers (``sphere_kernel.pack``), packed once per change."""
        return self._packed_once("hulls", self.hull_data())

    @property
    def sphere_bodies(self) -> np.ndarray:
        """The body (row of ``KernelData.speed``) of each sphere, (S,)."""
        self.sync()
        return self._sphere_body.copy()

    @property
    def num_spheres(self) -> int:
        return len(self._radius)

    # -------------------------------------------------------------------------- queries ----
    def sphere_centres(self, qs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Returns the spheres' centres p_WS (N, S, 3) for configurations qs (N, 7) and their
        outer radii (S,), m."""
        self.sync()
        T = self._transforms(np.atleast_2d(qs))  # (K, N, 4, 4)
        X = T[self._slot]  # (S, N, 4, 4)
        p = self._robot_arrays["p_BS"]
        p_WS = np.einsum("snij,sj->nsi", X[:, :, :3, :3], p) + X[:, :, :3, 3].transpose(1, 0, 2)
        return p_WS, self._radius.copy()

    def _transforms(self, qs: np.ndarray) -> np.ndarray:
        full = np.tile(self._template, (len(qs), 1))
        full[:, self._arm] = qs
        return self._kin.transforms(full)

    def classify(self, qs) -> np.ndarray:
        """Returns FREE, COLLIDING or UNKNOWN (int8 array) for each row of qs (N, 7), rad."""
        qs = np.ascontiguousarray(np.atleast_2d(qs), dtype=float)
        if self.active:  # in batches of configurations (the scalar kernel's verdicts)
            _kernel.announce_compile(classify_many)  # on stderr, once, when the first call compiles
            return classify_many(qs, self._data)
        return np.full(len(qs), UNKNOWN, dtype=np.int8)

    def prove_free(self, qs) -> np.ndarray:
        """True for each row of qs (N, 7) that the robot's exact shapes prove collision-free
        for Drake's checker (``hull_kernel``): what ``classify`` leaves UNKNOWN, decided
        without Drake where a separating plane shows it. False everywhere without a model."""
        qs = np.ascontiguousarray(np.atleast_2d(qs), dtype=float)
        if not self.active:
            return np.zeros(len(qs), dtype=bool)
        _kernel.announce_compile(prove_free_packed)
        return prove_free_packed(qs, *self.packed_data(), *self.packed_hulls())

    def prefixes(self, q_a, q_b, step: float, stop_at_unknown: bool):
        """Classifies samples of segments from their starts up to their first blocking one;
        see ``sphere_kernel.prefixes``. Without a sphere model every sample is UNKNOWN."""
        q_a = np.ascontiguousarray(np.atleast_2d(q_a), dtype=float)
        q_b = np.ascontiguousarray(np.atleast_2d(q_b), dtype=float)
        if self.active:
            _kernel.announce_compile()
            return _kernel.prefixes(q_a, q_b, float(step), stop_at_unknown, self._data)
        n = np.maximum(1, np.ceil(np.linalg.norm(q_b - q_a, axis=1) / step).astype(np.int64))
        if stop_at_unknown:
            return np.zeros(len(n), dtype=np.int64), n, np.zeros(0, int), np.zeros(0, int)
        edge = np.repeat(np.arange(len(n)), n)
        return n.copy(), n, edge, np.arange(len(edge)) - np.repeat(np.cumsum(n) - n, n)


def speed_table(parent, kind, q_index, terms, template, arm, body_step, point_norm):
    """A bound on the speed of the points of each body per rad of each arm joint, (L, 7), m/rad,
    valid in every configuration (``KernelData.speed``).

    Step s of the tree maps a point p of its child frame to X_PC(q) [p; 1] with
    X_PC = A + a B + b C (``sphere_fk``); for a revolute joint its derivative in q is
    (cos q B - sin q C) [p; 1], no longer than |[B; C] [p; 1]| <= sigma |p| + |t|, where sigma
    is the largest singular value of the stacked rotation parts of B and C (6 x 3) and t their
    stacked translations. The parent frame moves rigidly with the rest of the tree, so that is
    also the point's speed in the world. |p| in step s's frame is at most the point's distance
    from its body's origin (``point_norm``) plus the largest translation of every step between
    them. A prismatic arm joint gets no bound (inf)."""
    arm_of = {int(k): j for j, k in enumerate(arm)}
    A, B, C = terms[:, 0], terms[:, 1], terms[:, 2]  # (J, 3, 4) each
    sigma = np.linalg.norm(np.concatenate([B[:, :, :3], C[:, :, :3]], axis=1), 2, axis=(1, 2))
    shift = np.linalg.norm(np.concatenate([B[:, :, 3], C[:, :, 3]], axis=1), axis=1)
    # The largest translation of each step: a joint of the arm anywhere, another at the
    # template's position (a weld has a = b = 0).
    held = np.where(kind == 0, 0.0, template[q_index])
    a = np.where(kind == 1, np.sin(held), held)
    c = np.where(kind == 1, np.cos(held), 0.0)
    fixed = np.linalg.norm(A[:, :, 3] + a[:, None] * B[:, :, 3] + c[:, None] * C[:, :, 3], axis=1)
    moving = np.array([kind[s] != 0 and int(q_index[s]) in arm_of for s in range(len(kind))])
    largest = np.where(moving, np.linalg.norm(A[:, :, 3], axis=1) + shift, fixed)
    largest[moving & (kind == 2)] = np.inf  # a prismatic arm joint: no bound
    speed = np.zeros((len(body_step), len(arm)))
    for b, step in enumerate(body_step):
        reach = float(point_norm[b])
        s = int(step)
        while s >= 0:
            if moving[s]:
                speed[b, arm_of[int(q_index[s])]] = (
                    sigma[s] * reach + shift[s] if kind[s] == 1 else np.inf
                )
            reach += largest[s]
            s = int(parent[s])
    return np.ascontiguousarray(speed)


def _unfiltered_in_model(plant, inspector, bodies) -> set[tuple[int, int]]:
    """Pairs (a, b) of ``bodies`` (in that order) with a pair of collision geometries that the
    SceneGraph model does not filter. Read once: later changes go to the checker's own filter
    matrix (``allow_collision``, held objects) or concern shapes the checker adds, never the
    model's robot geometries."""
    geometries = {
        b: plant.GetCollisionGeometriesForBody(plant.get_body(BodyIndex(b))) for b in bodies
    }
    return {
        (a, b)
        for i, a in enumerate(bodies)
        for b in bodies[i + 1 :]
        if any(not inspector.CollisionFiltered(g, h) for g in geometries[a] for h in geometries[b])
    }


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


def _primitives(objects) -> np.ndarray:
    """World boxes, cylinders and spheres as the kernel's object rows (``KernelData``): object
    O as its kind, W = R_WO^T and offset = R_WO^T p_WO (so p_OQ = W p_WQ - offset), its sizes
    (box: half sizes; cylinder: radius, half length; sphere: radius) and the corners of an
    axis-aligned box around it, m."""
    objects = list(objects)
    kinds = {"box": 0, "cylinder": 1, "sphere": 2}
    W = np.array([o.X_PO.rotation().matrix().T for o in objects]).reshape(-1, 3, 3)
    p = np.array([o.X_PO.translation() for o in objects]).reshape(-1, 3)
    size = np.zeros((len(objects), 3))
    half = np.zeros((len(objects), 3))  # half extents along the object's own axes
    for k, o in enumerate(objects):
        if o.shape == "box":
            size[k] = half[k] = np.asarray(o.size) / 2
        elif o.shape == "cylinder":
            size[k, :2] = o.size[0], o.size[1] / 2
            half[k] = o.size[0], o.size[0], o.size[1] / 2
        else:
            size[k, 0] = o.size[0]
            half[k] = o.size[0]
    extent = np.einsum("kji,kj->ki", np.abs(W), half)  # |R_WO| half
    rows = np.zeros((len(objects), _kernel.OBJ_COLUMNS))
    rows[:, _kernel.OBJ_KIND] = [kinds[o.shape] for o in objects]
    rows[:, _kernel.OBJ_W : _kernel.OBJ_W + 9] = W.reshape(-1, 9)
    rows[:, _kernel.OBJ_OFFSET : _kernel.OBJ_OFFSET + 3] = np.einsum("kij,kj->ki", W, p)
    rows[:, _kernel.OBJ_SIZE : _kernel.OBJ_SIZE + 3] = size
    rows[:, _kernel.OBJ_LOWER : _kernel.OBJ_LOWER + 3] = p - extent
    rows[:, _kernel.OBJ_UPPER : _kernel.OBJ_UPPER + 3] = p + extent
    return rows
