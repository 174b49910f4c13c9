"""The Panda as a Drake planning model: arm, hand, two fingers and a slot for held objects.

``add_panda`` parses the cached Drake-ready URDF (``panda_assets.panda_urdf``) into a plant,
welds ``panda_link0`` to the world at the origin and adds ``panda_attachment``, a massless body
welded to ``panda_hand`` (at its frame) that carries objects attached to the hand, so that they
are checked against the arm links but not against the hand or the fingers holding them.
``apply_disabled_collisions`` declares the SRDF's disabled pairs as SceneGraph collision
filters, so every SceneGraph query (collision checker, IK and trajectory-optimisation distance
constraints) honours them. ``build_panda_model`` does both into a ``RobotDiagram``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.geometry import Box, CollisionFilterDeclaration, GeometrySet, Rgba
from pydrake.math import RigidTransform
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex, SpatialInertia
from pydrake.planning import RobotDiagram, RobotDiagramBuilder

from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import make_parser
from planning.model.assets import panda_urdf, read_srdf
from planning.model.layout import NUM_ARM_JOINTS
from planning.model.panda_config import PandaModelConfig, TableConfig

ARM_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))
"""The seven arm joints, base to flange."""
FINGER_JOINTS = ("panda_finger_joint1", "panda_finger_joint2")
"""The two finger joints (m from the hand's centre line each)."""
HAND_BODY = "panda_hand"
ATTACHMENT_BODY = "panda_attachment"
"""The body, welded to the hand, that carries attached objects."""


def add_panda(plant: MultibodyPlant, config: PandaModelConfig) -> ModelInstanceIndex:
    """Adds the Panda (welded at the world origin) and its attachment body to ``plant``.

    Args:
        plant: an unfinalized plant registered with a SceneGraph.
        config: which collision geometry to load.

    Returns:
        The Panda's model instance.
    """
    (instance,) = make_parser(plant).AddModels(str(panda_urdf(config.collision_geometry)))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("panda_link0", instance))
    attachment = plant.AddRigidBody(ATTACHMENT_BODY, instance, SpatialInertia.Zero())
    plant.WeldFrames(
        plant.GetFrameByName(HAND_BODY, instance), attachment.body_frame(), RigidTransform()
    )
    return instance


def add_table(plant: MultibodyPlant, table: TableConfig) -> None:
    """Welds a box table (collision and visual geometry) to the world of ``plant``.

    Planning scenes hold the table as a removable world object instead; this is for diagrams
    that simulate the Panda.
    """
    X_WT = RigidTransform(np.asarray(table.position, dtype=float))
    shape = Box(*table.size)
    world = plant.world_body()
    plant.RegisterCollisionGeometry(world, X_WT, shape, "table", CoulombFriction(0.8, 0.6))
    plant.RegisterVisualGeometry(world, X_WT, shape, "table", Rgba(0.55, 0.4, 0.25, 1.0).rgba)


def disabled_collision_pairs(config: PandaModelConfig) -> list[tuple[str, str]]:
    """Returns the SRDF's disabled link pairs plus the configuration's extra ones."""
    pairs = list(read_srdf().disabled_collisions)
    pairs += [(a, b) for a, b in config.extra_disabled_collisions]
    return pairs


def apply_disabled_collisions(
    plant: MultibodyPlant, scene_graph, instance: ModelInstanceIndex, pairs
) -> None:
    """Excludes collisions between each pair of link names in the SceneGraph model.

    Raises:
        ConfigError: a pair names a body the Panda does not have.
    """
    manager = scene_graph.collision_filter_manager()
    for name_a, name_b in pairs:
        bodies = []
        for name in (name_a, name_b):
            if not plant.HasBodyNamed(name, instance):
                raise ConfigError(f"disabled collision pair ({name_a}, {name_b}): no body {name}")
            bodies.append(plant.GetBodyByName(name, instance))
        sets = [GeometrySet(plant.GetCollisionGeometriesForBody(b)) for b in bodies]
        manager.Apply(CollisionFilterDeclaration().ExcludeBetween(sets[0], sets[1]))


@dataclass
class PandaModel:
    """A finalized planning model of the Panda and the indices planners need.

    Attributes:
        diagram: the RobotDiagram (plant and SceneGraph, plus a visualizer when built with one).
        instance: the Panda's model instance.
        arm_indices: positions of the 7 arm joints in the plant's q.
        finger_indices: positions of the 2 finger joints in the plant's q.
        named_configurations: name -> arm q (rad, 7 values), from the YAML and the SRDF.
        config: the configuration it was built from.
    """

    diagram: RobotDiagram
    instance: ModelInstanceIndex
    arm_indices: np.ndarray
    finger_indices: np.ndarray
    named_configurations: dict[str, np.ndarray]
    config: PandaModelConfig

    @property
    def plant(self) -> MultibodyPlant:
        return self.diagram.plant()

    @property
    def scene_graph(self):
        return self.diagram.scene_graph()


def build_panda_model(config: PandaModelConfig, *, meshcat=None) -> PandaModel:
    """Builds the Panda planning model with the SRDF's collision filters applied.

    Args:
        config: the model configuration.
        meshcat: when given, a MeshcatVisualizer (illustration role) is added to the diagram.
    """
    builder = RobotDiagramBuilder(time_step=0.0)
    plant, scene_graph = builder.plant(), builder.scene_graph()
    instance = add_panda(plant, config)
    plant.Finalize()
    apply_disabled_collisions(plant, scene_graph, instance, disabled_collision_pairs(config))
    if meshcat is not None:
        from pydrake.geometry import MeshcatVisualizer, MeshcatVisualizerParams

        params = MeshcatVisualizerParams(prefix="planning/robot")
        MeshcatVisualizer.AddToBuilder(builder.builder(), scene_graph, meshcat, params)
    names = [*ARM_JOINTS, *FINGER_JOINTS]
    indices = [plant.GetJointByName(n, instance).position_start() for n in names]
    if config.ee_frame and not plant.HasFrameNamed(config.ee_frame, instance):
        raise ConfigError(f"model.ee_frame: the Panda has no frame {config.ee_frame!r}")
    return PandaModel(
        diagram=builder.Build(),
        instance=instance,
        arm_indices=np.array(indices[:NUM_ARM_JOINTS]),
        finger_indices=np.array(indices[NUM_ARM_JOINTS:]),
        named_configurations=_named_configurations(config),
        config=config,
    )


def _named_configurations(config: PandaModelConfig) -> dict[str, np.ndarray]:
    named = {}
    for name, joints in read_srdf().group_states.items():
        if all(j in joints for j in ARM_JOINTS):
            named[name] = np.array([joints[j] for j in ARM_JOINTS])
    for name, q in config.named_configurations.items():
        named[name] = np.asarray(q, dtype=float)
    return named
