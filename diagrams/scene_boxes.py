"""The Panda station's scene boxes: the table, the obstacle and the object as plant bodies.

``add_scene_box`` adds a box of a scene file (``planning.io.scene_files.BoxSpec``) welded to the
world or as a free body; ``box_pose`` is its pose and ``contact_properties`` its friction and
stiffness. Builder helpers of ``diagrams.arm_station`` (nothing here is a system).
"""

import numpy as np
from pydrake.geometry import AddContactMaterial, Box, ProximityProperties, Rgba
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import RigidBody, SpatialInertia

from planning.io.scene_files import BoxSpec


def box_pose(box: BoxSpec) -> RigidTransform:
    """X_WB of a scene box: its centre, turned by its yaw about the world z axis."""
    return RigidTransform(RollPitchYaw(0.0, 0.0, box.yaw), np.asarray(box.position, dtype=float))


def add_scene_box(
    plant: MultibodyPlant,
    name: str,
    box: BoxSpec,
    *,
    friction: CoulombFriction,
    color: Rgba,
    free: bool,
    point_stiffness: float | None = None,
) -> RigidBody | None:
    """Adds a scene box: welded to the world, or a free body in its own model instance.

    Args:
        plant: the unfinalized plant.
        name: the box's name (and the model instance's for a free body).
        box: size (m), centre position in W (m), yaw (rad), mass (kg, free bodies only).
        friction: the box's Coulomb friction.
        color: its visual colour.
        free: a free body (its default pose is the box's pose) or a world-welded box.

    Returns:
        The free body, or None for a welded box.
    """
    shape = Box(*box.size)
    props = contact_properties(friction, point_stiffness)
    if not free:
        X_WB = box_pose(box)
        world = plant.world_body()
        plant.RegisterCollisionGeometry(world, X_WB, shape, name, props)
        plant.RegisterVisualGeometry(world, X_WB, shape, name, color.rgba)
        return None
    instance = plant.AddModelInstance(name)
    inertia = SpatialInertia.SolidBoxWithMass(box.mass, *box.size)
    body = plant.AddRigidBody(name, instance, inertia)
    plant.RegisterCollisionGeometry(body, RigidTransform(), shape, name, props)
    plant.RegisterVisualGeometry(body, RigidTransform(), shape, name, color.rgba)
    plant.SetDefaultFloatingBaseBodyPose(body, box_pose(box))
    return body


def contact_properties(
    friction: CoulombFriction, point_stiffness: float | None = None
) -> ProximityProperties:
    """Proximity properties with a friction and, when given, a point-contact stiffness (N/m)."""
    props = ProximityProperties()
    AddContactMaterial(friction=friction, point_stiffness=point_stiffness, properties=props)
    return props
