"""``BatchedCollisionChecker``: Drake's ``SceneGraphCollisionChecker``, shapes added in batches.

Drake's ``AddCollisionShapeToBody`` re-declares every body pair's collision filter in every
context after each shape it adds, ``ExcludeWithin`` each body's geometries included: on the
world body that is quadratic in the objects, so the 400th object of a scene took about 90 ms.
Here ``queue_shape`` and ``queue_removal`` only record a change (microseconds); ``flush`` then
removes and registers the shapes in every model context (``PerformOperationAgainstAllModel\
Contexts``) and declares for the new ones the filters the checker's own rule gives them (against
the bodies the checker filters their body with, and within their body unless it is the world,
whose anchored geometries are never paired), leaving every other filter as it was.

Any use of a public attribute of the checker flushes first, so every query sees every shape,
whether it goes through the ``PlanningScene`` or through a reference to the checker that a
planner kept. Registering still costs Drake time linear in the shapes already there (FCL refits
its tree of anchored geometries per shape), but now once per shape instead of a filter pass per
shape over all pairs. Shapes added this way are not in ``GetAllAddedCollisionShapes``.
"""

from __future__ import annotations

import copy

from pydrake.geometry import (
    CollisionFilterDeclaration,
    GeometryId,
    GeometryInstance,
    GeometrySet,
    ProximityProperties,
)
from pydrake.multibody.tree import BodyIndex
from pydrake.planning import SceneGraphCollisionChecker

_OWN = frozenset({"queue_shape", "queue_removal", "flush", "pending"})


class BatchedCollisionChecker(SceneGraphCollisionChecker):
    """A ``SceneGraphCollisionChecker`` whose shapes are queued, then registered together.

    Takes the keyword arguments of ``SceneGraphCollisionChecker``.
    """

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._plant = SceneGraphCollisionChecker.plant(self)
        self._adds: dict[GeometryId, tuple[BodyIndex, GeometryInstance]] = {}
        self._removals: list[GeometryId] = []

    def __getattribute__(self, name: str):
        if name[0] != "_" and name not in _OWN and _has_queued(self):
            object.__getattribute__(self, "flush")()
        return super().__getattribute__(name)

    @property
    def pending(self) -> int:
        """How many queued additions and removals wait for ``flush``."""
        return len(self._adds) + len(self._removals)

    def queue_shape(self, body_index: BodyIndex, shape, X_BG, label: str) -> GeometryId:
        """Queues a collision shape fixed to a body at ``X_BG`` and returns its geometry id.

        Args:
            body_index: the body the shape hangs on (the world body for a world object).
            shape: a ``pydrake.geometry.Shape``.
            X_BG: the shape's pose in the body frame.
            label: names the geometry in SceneGraph (with its id).
        """
        instance = GeometryInstance(X_BG, shape, "queued")
        instance.set_name(f"{label} ({instance.id()})")
        instance.set_proximity_properties(ProximityProperties())
        self._adds[instance.id()] = (body_index, instance)
        return instance.id()

    def queue_removal(self, geometry_id: GeometryId) -> None:
        """Queues the removal of a shape added by ``queue_shape`` (dropped if still queued)."""
        if self._adds.pop(geometry_id, None) is None:
            self._removals.append(geometry_id)

    def flush(self) -> None:
        """Applies the queued removals, then the queued shapes, to every model context."""
        adds, removals = self._adds, self._removals
        if not adds and not removals:
            return
        self._adds, self._removals = {}, []
        plant = self._plant
        source = plant.get_source_id()
        declaration = self._filters(adds)
        shapes = [(plant.GetBodyFrameIdOrThrow(b), g) for b, g in adds.values()]

        def operation(model, context) -> None:
            scene_graph, sg_context = model.scene_graph(), context.scene_graph_context()
            for geometry_id in removals:
                scene_graph.RemoveGeometry(sg_context, source, geometry_id)
            for frame_id, instance in shapes:
                scene_graph.RegisterGeometry(sg_context, source, frame_id, copy.copy(instance))
            if shapes:
                scene_graph.collision_filter_manager(sg_context).Apply(declaration)

        SceneGraphCollisionChecker.PerformOperationAgainstAllModelContexts(self, operation)

    def _filters(self, adds) -> CollisionFilterDeclaration:
        """The filters of new shapes: against every body the checker filters with theirs, and
        within their body (but the world's)."""
        plant = self._plant
        world = plant.world_body().index()
        by_body: dict[BodyIndex, list[GeometryId]] = {}
        for geometry_id, (body_index, _) in adds.items():
            by_body.setdefault(body_index, []).append(geometry_id)
        declaration = CollisionFilterDeclaration()
        for body_index, ids in by_body.items():
            frame = plant.GetBodyFrameIdOrThrow(body_index)
            if body_index != world:
                declaration.ExcludeWithin(GeometrySet(ids, [frame]))
            others = [
                plant.GetBodyFrameIdOrThrow(BodyIndex(j))
                for j in range(plant.num_bodies())
                if j != body_index
                and SceneGraphCollisionChecker.IsCollisionFilteredBetween(
                    self, body_index, BodyIndex(j)
                )
            ]
            if others:
                declaration.ExcludeBetween(GeometrySet(ids), GeometrySet(others))
        return declaration


def _has_queued(checker: BatchedCollisionChecker) -> bool:
    get = object.__getattribute__
    return bool(get(checker, "_adds") or get(checker, "_removals"))
