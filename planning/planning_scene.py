"""The planning scene: a robot, world objects and objects it holds, with fast queries.

The robot model (``planning.model.planning_model``: the Panda unless the configuration names
another description) is built once; objects are added to and removed from the model of a
``BatchedCollisionChecker`` (Drake's ``SceneGraphCollisionChecker``, one geometry per object,
registered in every checker context before the next query: adding costs about the same at 400
objects as at 10, see ``benchmarks/scene_scale_benchmark.py``), never rebuilding the plant.
World objects hang on the world body; attached objects hang on ``<robot>_attachment``, a body
welded to the description's attach link (the Panda's hand), so they move with it, are checked
against the world and the robot's other links, and not against the attach link and the links
below it (filtered in the SceneGraph model, see ``planning_model``).

World objects are not checked against the robot's root link: it is welded to the world, and
Drake filters collisions within a welded group.

Configurations ``q`` are the planning group's joints (``model.num_joints`` values, in the
group's order: the Panda's 7 arm joints), with every other joint at ``other_positions``, or all
of the plant's positions.
"""

from __future__ import annotations

import collections
import dataclasses

import numpy as np
from pydrake.geometry import GeometryId
from pydrake.math import RigidTransform

from planning.collision.batched_checker import BatchedCollisionChecker
from planning.config import PlanningConfig
from planning.errors import ErrorCode, PlanningError
from planning.io import scene_files
from planning.model.planning_model import PlanningModel, build_planning_model
from planning.scene_objects import SceneObject
from planning.scene_positions import ScenePositions

_WORLD_PREFIX = "world/"
_ATTACHED_PREFIX = "attached/"


class PlanningScene(ScenePositions):
    """A robot, the objects around it and the objects it holds.

    Configurations ``q`` are the group's joints, with the other joints at ``other_positions``,
    or all of the plant's positions (the Panda: 7 arm joints, or those and its 2 fingers).

    Args:
        config: the planning configuration; ``PlanningConfig()`` when None. Its ``table``
            becomes the world object "table".
        meshcat: when given, ``publish`` shows the scene there.
    """

    def __init__(self, config: PlanningConfig | None = None, *, meshcat=None):
        self._config = config if config is not None else PlanningConfig()
        model = build_planning_model(self._config.model, meshcat=meshcat)
        options = self._config.model
        self._checker = BatchedCollisionChecker(
            model=model.diagram,
            robot_model_instances=[model.instance],
            edge_step_size=options.edge_step_size,
            env_collision_padding=options.env_collision_padding,
            self_collision_padding=options.self_collision_padding,
        )
        self._model = dataclasses.replace(model, diagram=self._checker.model())
        self._plant = self._checker.plant()
        self._meshcat = meshcat
        self._world: dict[str, SceneObject] = {}
        self._attached: dict[str, SceneObject] = {}
        self._other_positions = model.default_other.copy()
        # A context of our own to name colliding geometries and evaluate poses.
        self._context = self._checker.MakeStandaloneModelContext()
        self._geometry_names: dict[GeometryId, str] = {}  # object names of added geometries
        self._geometry_ids: dict[str, GeometryId] = {}  # by group, "world/name" or "attached/name"
        self.version = 0  # bumped by every change of objects, fingers or allowed pairs
        # Sphere models of the robot in this scene, by cover slack (m); built on first use by
        # planning.collision.sphere_checker.sphere_model and owned by the scene.
        self.sphere_models: dict[float, object] = {}
        # The checker filters body pairs: declare the SRDF's pairs there too, so that shapes
        # added later (held objects on the attachment body) are filtered as well.
        for link_a, link_b in model.disabled_pairs:
            self.allow_collision(link_a, link_b)
        self._robot_filters = self._checker.GetFilteredCollisionMatrix().copy()  # the robot's own
        # Held objects may touch world objects (they rest on the table when grasped and when
        # placed): a negative padding between the attachment body and the world.
        self._checker.SetPaddingBetween(
            self._attachment_body().index(),
            self.plant.world_body().index(),
            options.env_collision_padding - options.held_object_touch_tolerance,
        )
        self.place_position: np.ndarray | None = None  # p_W of a place target, m, if any
        if self._config.table is not None:
            table = self._config.table
            self.add_box("table", table.size, RigidTransform(np.asarray(table.position)))

    # ----------------------------------------------------------------------------- model ----
    @property
    def config(self) -> PlanningConfig:
        return self._config

    @property
    def model(self) -> PlanningModel:
        """The robot model (its ``diagram`` is owned by the collision checker)."""
        return self._model

    @property
    def plant(self):
        return self._plant

    @property
    def checker(self) -> BatchedCollisionChecker:
        """The scene's Drake ``SceneGraphCollisionChecker``, every object registered (queued ones
        now, later ones before any use from Python: C++ code holding it sees later changes
        once the scene or the checker is next used from Python)."""
        self._checker.flush()
        return self._checker

    @property
    def meshcat(self):
        return self._meshcat

    def plant_context(self, q):
        """Returns a plant context of this scene's model at q (shared scratch: do not keep it)."""
        return self._checker.UpdateContextPositions(self._context, self.full_q(q))

    # --------------------------------------------------------------------------- objects ----
    @property
    def world_objects(self) -> dict[str, SceneObject]:
        """World objects by name; their ``X_PO`` is ``X_WO``."""
        return dict(self._world)

    @property
    def attached_objects(self) -> dict[str, SceneObject]:
        """Held objects by name; their ``X_PO`` is ``X_AO`` in the hand's attachment frame A."""
        return dict(self._attached)

    def has_object(self, name: str) -> bool:
        return name in self._world or name in self._attached

    def add_object(self, obj: SceneObject) -> None:
        """Adds a world object (``obj.X_PO`` is its pose in the world).

        Raises:
            PlanningError: INVALID_OBJECT_NAME when the name is taken.
        """
        self._check_new(obj.name)
        self._add_geometry(_WORLD_PREFIX + obj.name, self.plant.world_body(), obj)
        self._world[obj.name] = obj

    def add_box(self, name: str, size, X_WO: RigidTransform) -> None:
        """Adds a box of full extents ``size`` (m) centred at ``X_WO``."""
        self.add_object(SceneObject(name, "box", tuple(size), X_WO))

    def add_cylinder(self, name: str, radius: float, length: float, X_WO: RigidTransform) -> None:
        """Adds a cylinder (m) along the z axis of ``X_WO``, centred at its origin."""
        self.add_object(SceneObject(name, "cylinder", (radius, length), X_WO))

    def add_sphere(self, name: str, radius: float, X_WO: RigidTransform) -> None:
        """Adds a sphere of ``radius`` (m) centred at the origin of ``X_WO``."""
        self.add_object(SceneObject(name, "sphere", (radius,), X_WO))

    def remove_object(self, name: str) -> SceneObject:
        """Removes a world or attached object and returns it.

        Raises:
            PlanningError: INVALID_OBJECT_NAME when there is no such object.
        """
        if name in self._world:
            self._remove_geometry(_WORLD_PREFIX + name)
            return self._world.pop(name)
        if name in self._attached:
            self._remove_geometry(_ATTACHED_PREFIX + name)
            return self._attached.pop(name)
        raise PlanningError(ErrorCode.INVALID_OBJECT_NAME, self._unknown(name))

    def move_object(self, name: str, X_WO: RigidTransform) -> None:
        """Moves a world object to a new pose."""
        obj = self._world.get(name)
        if obj is None:
            raise PlanningError(ErrorCode.INVALID_OBJECT_NAME, self._unknown(name))
        self.remove_object(name)
        self.add_object(obj.with_pose(X_WO))

    def clear(self) -> None:
        """Removes every world object (the table too); held objects stay."""
        for name in list(self._world):
            self.remove_object(name)

    def attach(self, name: str, q) -> None:
        """Attaches a world object to the hand, keeping its pose relative to the hand at q.

        Raises:
            PlanningError: INVALID_OBJECT_NAME when there is no such world object.
        """
        obj = self._world.get(name)
        if obj is None:
            raise PlanningError(ErrorCode.INVALID_OBJECT_NAME, self._unknown(name, "world "))
        X_WA = self.attachment_pose(q)
        self.remove_object(name)
        held = obj.with_pose(X_WA.inverse() @ obj.X_PO)
        self._add_geometry(_ATTACHED_PREFIX + name, self._attachment_body(), held)
        self._attached[name] = held

    def attach_new(self, obj: SceneObject) -> None:
        """Attaches a new object given in the attachment frame A (``obj.X_PO`` is ``X_AO``)."""
        self._check_new(obj.name)
        self._add_geometry(_ATTACHED_PREFIX + obj.name, self._attachment_body(), obj)
        self._attached[obj.name] = obj

    def detach(self, name: str, q) -> None:
        """Puts a held object back in the world at its pose when the robot is at q."""
        obj = self._attached.get(name)
        if obj is None:
            raise PlanningError(ErrorCode.INVALID_OBJECT_NAME, self._unknown(name, "attached "))
        X_WO = self.attachment_pose(q) @ obj.X_PO
        self.remove_object(name)
        self.add_object(obj.with_pose(X_WO))

    def object_pose(self, name: str, q=None) -> RigidTransform:
        """Returns X_WO of a world object, or of a held one with the robot at q."""
        if name in self._world:
            return self._world[name].X_PO
        if name in self._attached:
            if q is None:
                raise ValueError(f"the pose of the held object {name!r} needs q")
            return self.attachment_pose(q) @ self._attached[name].X_PO
        raise PlanningError(ErrorCode.INVALID_OBJECT_NAME, self._unknown(name))

    def attachment_pose(self, q) -> RigidTransform:
        """Returns X_WA, the pose of the attachment frame (the hand frame) at q."""
        return self._plant.EvalBodyPoseInWorld(self.plant_context(q), self._attachment_body())

    # --------------------------------------------------------------------------- queries ----
    def is_collision_free(self, q) -> bool:
        """True when q has no collision (self or environment, held objects included)."""
        return self._checker.CheckConfigCollisionFree(self.full_q(q))

    def is_edge_collision_free(self, q_a, q_b) -> bool:
        """True when the straight joint-space segment is collision-free at the edge step."""
        return self._checker.CheckEdgeCollisionFree(self.full_q(q_a), self.full_q(q_b))

    def in_joint_limits(self, q, tolerance: float = 1e-9) -> bool:
        """True when every joint of the group is within its limits at q (the others are not
        checked)."""
        q = self.arm_q(q)
        lower, upper = self.lower - tolerance, self.upper + tolerance
        return bool(np.all(q >= lower) and np.all(q <= upper))

    def colliding_pairs(self, q) -> list[tuple[str, str]]:
        """Returns the pairs of names (robot links, object names) in collision at q, sorted:
        those closer than their padding (so touching pairs count when the padding is 0, and a
        held object may sink ``held_object_touch_tolerance`` into the world)."""
        self._checker.UpdateContextPositions(self._context, self.full_q(q))
        query_object = self._context.GetQueryObject()
        reach = max(self._checker.GetLargestPadding(), 0.0) + 1e-9
        pairs = set()
        for pair in query_object.ComputeSignedDistancePairwiseClosestPoints(reach):
            name_a, body_a = self._describe(query_object, pair.id_A)
            name_b, body_b = self._describe(query_object, pair.id_B)
            if body_a == body_b or self._checker.IsCollisionFilteredBetween(body_a, body_b):
                continue
            if pair.distance <= self._checker.GetPaddingBetween(body_a, body_b) + 1e-9:
                pairs.add(tuple(sorted((name_a, name_b))))
        return sorted(pairs)

    def distance_to_links(self, name: str, links, q, reach: float) -> float:
        """The smallest signed distance (m) from object ``name`` to the robot links ``links``
        at q, or ``reach`` when none is closer than that."""
        self._checker.UpdateContextPositions(self._context, self.full_q(q))
        query_object, links = self._context.GetQueryObject(), set(links)
        best = reach
        for pair in query_object.ComputeSignedDistancePairwiseClosestPoints(reach):
            names = {self._describe(query_object, i)[0] for i in (pair.id_A, pair.id_B)}
            if name in names and names & links:
                best = min(best, pair.distance)
        return float(best)

    def describe_collisions(self, q) -> str:
        """Returns "a <-> b, c <-> d" for the colliding pairs at q ("" when there are none)."""
        return ", ".join(f"{a} <-> {b}" for a, b in self.colliding_pairs(q))

    def clearance(self, q, influence_distance: float = 1.0) -> float:
        """Returns the smallest signed distance (m) between unfiltered pairs at q.

        Negative is penetration; ``influence_distance`` when nothing is closer than that.
        """
        result = self._checker.CalcRobotClearance(self.full_q(q), influence_distance)
        distances = result.distances()
        return float(distances.min()) if len(distances) else float(influence_distance)

    def allow_collision(self, link_a: str, link_b: str) -> None:
        """Stops checking two robot links against each other (a MoveIt ACM entry).

        Raises:
            PlanningError: INVALID_OBJECT_NAME for an unknown link.
        """
        a, b = self._link_index(link_a), self._link_index(link_b)
        if a != b:
            self._checker.SetCollisionFilteredBetween(a, b, True)
            self.version += 1

    def replace(self, world=(), attached=(), allowed=()) -> None:
        """Replaces the whole scene: the world objects (the table too) by ``world``, the held
        ones by ``attached`` (poses in the attachment frame A), the allowed collisions by the
        robot's own plus the ``allowed`` pairs of link names; clears ``place_position``.

        Raises:
            PlanningError: INVALID_OBJECT_NAME (a name used twice, an unknown link): no change.
        """
        names = collections.Counter(o.name for o in [*world, *attached])
        if duplicates := sorted(n for n, k in names.items() if k > 1):
            raise PlanningError(ErrorCode.INVALID_OBJECT_NAME, f"duplicate names {duplicates}")
        filters = self._robot_filters.copy()
        for link_a, link_b in allowed:
            a, b = self._link_index(link_a), self._link_index(link_b)
            filters[a, b] = filters[b, a] = a != b
        for name in [*self._world, *self._attached]:
            self.remove_object(name)
        self._checker.SetCollisionFilterMatrix(filters)
        for obj in world:
            self.add_object(obj)
        for obj in attached:
            self.attach_new(obj)
        self.place_position = None
        self.version += 1

    def load_yaml(self, filename) -> None:
        """Replaces the whole scene by our scene YAML (``planning.io.scene_files``)."""
        scene_files.load_scene_yaml(self, filename)

    def load_moveit(self, filename, *, strict: bool = False, package_paths=None):
        """Replaces the whole scene by a MoveIt scene: a PlanningScene YAML (``.yaml``, ``.yml``)
        or the text format (``.scene``); see ``planning.io.moveit_scene``. What MoveIt would
        load but this cannot represent is left out with one warning per object (an error with
        ``strict``). Returns the ``MoveItScene`` (its start state, warnings, skipped objects)."""
        return scene_files.load_moveit_scene(
            self, filename, strict=strict, package_paths=package_paths
        )

    def save_yaml(self, filename) -> None:
        """Writes the scene in our YAML (``planning.io.scene_files``)."""
        scene_files.save_scene_yaml(self, filename)

    def publish(self, q) -> None:
        """Shows the robot at q and every object in Meshcat (when the scene has one)."""
        from planning.scene_display import publish_scene

        publish_scene(self, q)

    # --------------------------------------------------------------------------- private ----
    def _attachment_body(self):
        return self.plant.GetBodyByName(self._model.attachment_body, self._model.instance)

    def _add_geometry(self, group: str, body, obj: SceneObject) -> None:
        self.version += 1
        geometry_id = self._checker.queue_shape(body.index(), obj.drake_shape(), obj.X_PO, group)
        self._geometry_ids[group] = geometry_id
        self._geometry_names[geometry_id] = obj.name

    def _remove_geometry(self, group: str) -> None:
        self.version += 1
        geometry_id = self._geometry_ids.pop(group)
        self._checker.queue_removal(geometry_id)
        del self._geometry_names[geometry_id]

    def _check_new(self, name: str) -> None:
        if self.has_object(name):
            raise PlanningError(
                ErrorCode.INVALID_OBJECT_NAME, f"the scene already has an object {name!r}"
            )

    def _link_index(self, name: str):
        if not self._plant.HasBodyNamed(name, self._model.instance):
            raise PlanningError(
                ErrorCode.INVALID_OBJECT_NAME, f"{self._model.robot.name} has no link {name!r}"
            )
        return self._plant.GetBodyByName(name, self._model.instance).index()

    def _describe(self, query_object, geometry_id):
        body = self._plant.GetBodyFromFrameId(query_object.inspector().GetFrameId(geometry_id))
        return self._geometry_names.get(geometry_id, body.name()), body.index()

    def _unknown(self, name: str, kind: str = "") -> str:
        known = {"": [*self._world, *self._attached], "world ": self._world}
        known = known.get(kind, self._attached)
        return f"no {kind}object named {name!r}; the scene has {sorted(known)}"
