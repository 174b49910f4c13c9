"""The simulated Panda of the stations: arm, hand, two fingers and a slot for held objects.

``add_panda`` parses the cached Drake-ready URDF (``panda_assets.panda_urdf``) into a plant,
welds ``panda_link0`` to the world at the origin and adds ``panda_attachment``, a massless body
welded to ``panda_hand`` (at its frame) that carries objects attached to the hand, so that they
are checked against the arm links but not against the hand or the fingers holding them.
``disabled_collision_pairs`` lists the pairs the stations declare as SceneGraph collision
filters (``planning_model.apply_disabled_collisions``). Planning builds its robot from a
description instead (``planning.model.planning_model``; the Panda's is
``config/robots/panda.yaml``).
"""

from __future__ import annotations

import numpy as np
from pydrake.geometry import Box, Rgba
from pydrake.math import RigidTransform
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex, SpatialInertia

from drake_sim.base.resources import make_parser
from planning.model.assets import panda_urdf, read_srdf
from planning.model.model_config import RobotModelConfig, TableConfig

ARM_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))
"""The seven arm joints, base to flange."""
FINGER_JOINTS = ("panda_finger_joint1", "panda_finger_joint2")
"""The two finger joints (m from the hand's centre line each)."""
HAND_BODY = "panda_hand"
ATTACHMENT_BODY = "panda_attachment"
"""The body, welded to the hand, that carries attached objects."""


def add_panda(plant: MultibodyPlant, config: RobotModelConfig) -> ModelInstanceIndex:
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


def disabled_collision_pairs(config: RobotModelConfig) -> list[tuple[str, str]]:
    """Returns the SRDF's disabled link pairs, the attachment body against the hand's fingers
    (held objects never collide with the fingers holding them), and the configuration's extra
    pairs."""
    pairs = list(read_srdf().disabled_collisions)
    pairs += [(ATTACHMENT_BODY, finger) for finger in ("panda_leftfinger", "panda_rightfinger")]
    pairs += [(a, b) for a, b in config.extra_disabled_collisions]
    return pairs
