"""Fast collision checks of many configurations of a robot's planning group with sphere models.

The robot's collision geometry (its links, the joints outside the group at the scene's
positions, and held objects) is covered by spheres (``sphere_robot``); world objects stay exact
boxes, cylinders and spheres. ``SphereCollisionModel.classify`` runs forward kinematics for each
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
inner test; the outer test uses at least zero. The robot's own pairs proven apart everywhere are
left out, and those with a clearance table skip their sphere tests where it proves them apart
(``self_pairs``, ``pair_tables``).

Costs: each body's spheres are cut into groups of up to ``sphere_arrays.GROUP`` neighbours with
a bounding sphere; only groups (and group pairs) with anything near reach the per-sphere pass,
and a configuration stops at its first certain collision. Every comparison has a margin of
``sphere_arrays.MARGIN`` on the safe side (``sphere_arrays`` makes the kernels' arrays). World
objects are re-read whenever the scene's objects change, the robot's spheres whenever held
objects or filters change, and the robot's part of the kernel data (its folded kinematics,
speed bounds) when those or the finger positions change.
"""

from __future__ import annotations

import numpy as np
from pydrake.multibody.tree import BodyIndex

from planning.collision import sphere_kernel as _kernel
from planning.collision.checker import speed_walk
from planning.collision.hull_kernel import HullData, prove_free_packed
from planning.collision.pair_tables import kernel_fields
from planning.collision.self_pairs import OwnPairs
from planning.collision.sphere_arrays import (
    Filters,
    body_groups,
    folded_hulls,
    hull_arrays,
    primitives,
    robot_arrays,
    shape_reach,
)
from planning.collision.sphere_batch import classify_many
from planning.collision.sphere_cover import SphereSet
from planning.collision.sphere_fk import BatchedKinematics, fold_fixed_steps, fold_points
from planning.collision.sphere_kernel import COLLIDING, FREE, UNKNOWN, KernelData
from planning.collision.sphere_robot import (
    held_cover,
    robot_hulls,
    robot_spheres,
    shape_hull,
    unfiltered_in_model,
)

__all__ = ["COLLIDING", "FREE", "UNKNOWN", "SphereCollisionModel"]
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
        model = scene.model
        self._attachment = int(plant.GetBodyByName(model.attachment_body, model.instance).index())
        self._held_cache: dict[tuple, SphereSet] = {}
        self._groups_cache: dict[int, tuple] = {}  # body -> _body_groups
        self._signature = self._held_signature = self._robot_signature = self._version = None
        self._packed = {}  # "kernel" or "hulls" -> (the data, its packed buffers)
        self._alive = {}  # signature name -> the objects it names (see ``sync``)
        self._stale_version = None  # the scene's version whose robot part sync left undone
        self.supported = True
        self._never: set[frozenset] | None = None  # own pairs never close, once known
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
            self._unfiltered = unfiltered_in_model(plant, query.inspector(), self._bodies)
            self._kin = BatchedKinematics(plant, self._bodies)
            self._own = OwnPairs(
                plant, scene.model.arm_indices, set(self._robot) - {self._attachment}
            )
        except NotImplementedError:
            self.supported = False
        self.sync()
        # Compiles or loads the kernels now, not mid-request.
        zero = np.zeros((1, scene.num_joints))
        self.classify(zero)
        self.prefixes(zero, zero, 1.0, False)

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
            tuple(scene.other_positions),
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
        self._template = scene.full_q(np.zeros(scene.num_joints))
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
                if self._never is None:  # once: then the arrays without them, with the tables
                    data, present = self._kernel_robot(), self._present
                    self._never = self._own.never(data, self._hull_data, present)
                    if self._never:
                        self._build_robot(held)
                    self._robot_data = self._robot_kernel_arrays()
                self._robot_signature = signature[1:]
                self._alive["robot"] = objects[1]
            self._data = KernelData(**self._robot_data, objects=primitives(world.values()))
        return True

    def _robot_kernel_arrays(self) -> dict:
        """The ``KernelData`` fields other than ``objects`` (they depend on the robot, its held
        objects and the finger positions alone, not on the world's objects)."""
        template = np.ascontiguousarray(self._template, dtype=float)
        arm = np.asarray(self._arm, dtype=np.int64)
        # The kernels run the tree with its fixed steps folded away (the fingers too, at the
        # template's positions): the points those steps carried move into the frames of the
        # steps that carry them now.
        tree, offsets = fold_fixed_steps(*self._kin.arrays(), template, arm)
        arrays = dict(self._robot_arrays)
        # Speed bounds walked up the plant's tree (``checker.speed_walk``; 1.4x tighter on the
        # Panda than ``sphere_arrays.speed_table``'s on the folded tree): of the points the
        # checks use, and of the exact shapes' points, farther out than the spheres' centres
        # (``shape_reach``) and within the spheres, which contain them (if the cover is loose).
        plant, present = self._scene.plant, self._present
        columns = {int(k): j for j, k in enumerate(arm)}
        speed = speed_walk(plant, columns, dict(zip(present, self._point_norm, strict=True)))
        reach = np.maximum(self._shape_reach, self._sphere_reach)
        geometry_speed = speed_walk(plant, columns, dict(zip(present, reach, strict=True)))
        # The shapes' own bound, the same for every cover: the clearance tables use it, so
        # the covers of one robot share their tables' costly cells (``pair_tables``).
        shape_speed = speed_walk(plant, columns, dict(zip(present, self._shape_reach, strict=True)))
        for steps, points in _FOLDED:
            arrays[steps], arrays[points] = fold_points(offsets, arrays[steps], arrays[points])
        self._hull_data = folded_hulls(self._hull_raw, offsets, geometry_speed)
        out = dict(
            zip(("parent", "kind", "q_index", "terms"), tree, strict=True),
            template=template,
            arm=arm,
            **arrays,
            speed=np.ascontiguousarray(speed),
            **{name: np.sqrt(np.maximum(arrays[squared], 0.0)) for name, squared in _ROOTS.items()},
            **kernel_fields([None] * len(arrays["body_pair"])),
        )
        if self._never is not None:  # the own pairs' clearance tables (``pair_tables``)
            shapes = self._hull_data._replace(speed=shape_speed)
            tables = self._own.tables(self._kernel_robot(out), shapes, self._present)
            out.update(kernel_fields(tables))
        return out

    def _kernel_robot(self, robot_data: dict | None = None) -> KernelData:
        """``KernelData`` of the robot's part (``_robot_data``, or ``robot_data``) alone."""
        return KernelData(**(robot_data or self._robot_data), objects=primitives(()))

    def _build_robot(self, held) -> None:
        """Remakes the robot's arrays (``sphere_arrays``) for the held objects ``held``."""
        sets = dict(self._robot)
        held_sets = [self._held(obj) for obj in held.values()]
        if held_sets:
            sets[self._attachment] = SphereSet.concat(held_sets)
        present = list(sets)
        slot = {b: k for k, b in enumerate(self._bodies)}
        step = self._kin.out  # kinematic step of each of self._bodies
        filters = Filters(
            self._filtered, self._padding, self._world, self._checked_body_pairs(present)
        )
        shapes = {b: list(self._hulls.get(b, [])) for b in present}
        if held:
            shapes[self._attachment] = [shape_hull(o.drake_shape(), o.X_PO) for o in held.values()]
        self._hull_raw = hull_arrays(shapes, step, slot, filters)
        robot = robot_arrays(sets, self._body_groups, step, slot, filters)
        self._slot, self._sphere_body = robot.sphere_slot, robot.sphere_body
        self._radius, self._point_norm = robot.radius, robot.point_norm
        self._shape_reach = shape_reach(shapes)
        p_BS = robot.arrays["p_BS"]
        ends = np.linalg.norm(p_BS, axis=1) + robot.radius  # each sphere's farthest point
        self._sphere_reach = np.zeros(len(present))
        np.maximum.at(self._sphere_reach, robot.sphere_body, ends)
        self._present = present
        self._robot_arrays = robot.arrays

    def _body_groups(self, body: int, spheres: SphereSet):
        """``sphere_arrays.body_groups`` of a body's spheres, kept for the robot's own bodies,
        whose spheres never change."""
        if body in self._groups_cache and body != self._attachment:
            return self._groups_cache[body]
        out = body_groups(spheres)
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
                if self._filtered[a, b] != 0 or frozenset((a, b)) in (self._never or ()):
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
        """Returns the spheres' centres p_WS (N, S, 3) for configurations qs (N, D) and their
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

    def classify(self, qs, motion=None) -> np.ndarray:
        """Returns FREE, COLLIDING or UNKNOWN (int8 array) for each row of qs (N, D), rad.
        ``motion`` (N, D), rad: FREE then also says that every configuration within motion[n, j]
        of row n in each joint j is free (``sphere_batch.classify_many``)."""
        qs = np.ascontiguousarray(np.atleast_2d(qs), dtype=float)
        if self.active:  # in batches of configurations (the scalar kernel's verdicts)
            _kernel.announce_compile(classify_many)  # on stderr, once, when the first call compiles
            return classify_many(qs, self._data, _motion(motion, qs))
        return np.full(len(qs), UNKNOWN, dtype=np.int8)

    def prove_free(self, qs, motion=None) -> np.ndarray:
        """True for each row of qs (N, D) that the robot's exact shapes prove collision-free
        for Drake's checker (``hull_kernel``): what ``classify`` leaves UNKNOWN, decided
        without Drake where a separating plane shows it. False everywhere without a model.
        ``motion`` as ``classify``'s."""
        qs = np.ascontiguousarray(np.atleast_2d(qs), dtype=float)
        if not self.active:
            return np.zeros(len(qs), dtype=bool)
        _kernel.announce_compile(prove_free_packed)
        packed = (*self.packed_data(), *self.packed_hulls())
        return prove_free_packed(qs, *packed, _motion(motion, qs))

    def geometry_speed(self) -> tuple[list[int], np.ndarray] | None:
        """(body indices, (B, D) speed bounds of their collision geometry's points, m/rad), for
        margins on Drake's distances (``checker.swept_free``); None without a model."""
        if not self.supported:
            return None
        self.sync()
        return list(self._present), self._hull_data.speed

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


def _motion(motion, qs: np.ndarray) -> np.ndarray:
    """The kernels' ``motion`` argument: (N, D) float64, or (0, D) for none."""
    if motion is None:
        return np.zeros((0, qs.shape[1]))
    return np.array(np.broadcast_to(motion, qs.shape), dtype=float)  # writeable: one signature
