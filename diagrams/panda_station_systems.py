"""Small helpers of the Panda station: a free body's pose from its positions, and the object."""

import numpy as np
from pydrake.common.value import Value
from pydrake.geometry import AddContactMaterial, Box, ProximityProperties, Rgba
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import RigidBody, SpatialInertia
from pydrake.systems.framework import LeafSystem

from planning.io.scene_files import BoxSpec
from planning.scene_objects import FREE_BODY_POSITIONS, free_body_pose


class FreeBodyPose(LeafSystem):
    """Outputs a free body's pose from its positions [qw, qx, qy, qz, x, y, z].

    .. pydrake_system::

        name: FreeBodyPose
        input_ports:
        - positions
        output_ports:
        - pose

    ``positions`` is a vector whose first 7 entries are the body's quaternion (w, x, y, z) and
    position p_WB (m), e.g. a plant's state output port of a model instance holding one free
    body (13 values); ``pose`` is the abstract RigidTransform X_WB. Evaluated on demand only.
    """

    def __init__(self, *, input_size: int = 7):
        super().__init__()
        if input_size < 7:
            raise ValueError(f"positions needs at least 7 values, got input_size={input_size}")
        self._input = self.DeclareVectorInputPort("positions", input_size)
        self.DeclareAbstractOutputPort("pose", lambda: Value(RigidTransform()), self.CalcPose)

    def CalcPose(self, context, output) -> None:
        output.set_value(free_body_pose(self._input.Eval(context)[:FREE_BODY_POSITIONS]))


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
