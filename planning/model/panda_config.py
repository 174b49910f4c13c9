"""How the Panda is loaded for planning, and the table a new scene starts with.

The ``model`` and ``table`` sections of ``planning.config.PandaPlanningConfig`` (the ``robot``
section of the pick-and-place scenario), kept with the model that reads them
(``planning.model.panda``). Every field has a default; joint positions in rad (arm) and m
(fingers), lengths in m. No ``from __future__ import annotations``: the YAML loader reads the
field types at run time.
"""

import dataclasses as dc
import math

from planning.model.layout import FINGER_OPEN, READY_Q


@dc.dataclass
class TableConfig:
    """A box table in the world frame W, by default under the Panda with its top at z = 0."""

    size: list[float] = dc.field(default_factory=lambda: [1.2, 1.4, 0.04])  # m, full extents
    position: list[float] = dc.field(default_factory=lambda: [0.3, 0.0, -0.02])  # m, p_WT centre


@dc.dataclass
class PandaModelConfig:
    """How the Panda is loaded for planning."""

    # "convex_mesh" (the URDF's STL collision meshes, declared convex) or "primitives" (the
    # spheres and cylinders of example-robot-data's panda_collision.urdf).
    collision_geometry: str = "convex_mesh"
    # Frame whose pose RobotState reports and IK targets: the tool centre point between the
    # fingertips, 0.1034 m beyond the hand's flange side along its z axis (MoveIt's end effector).
    ee_frame: str = "panda_hand_tcp"
    # Default opening of each finger, m from the centre (0 closed, 0.04 fully open).
    finger_position: float = FINGER_OPEN
    # Named arm configurations, rad, 7 joints each; the SRDF's group_state entries are added
    # (a name here wins over the SRDF).
    named_configurations: dict[str, list[float]] = dc.field(
        default_factory=lambda: {
            "ready": list(READY_Q),  # franka "ready"
            "extended": [0.0, 0.6, 0.0, -0.9, 0.0, 1.5, math.pi / 4],  # reaching forward
            "transport": [0.0, -0.9, 0.0, -2.8, 0.0, 1.9, math.pi / 4],  # folded, hand up close
        }
    )
    # Link pairs never checked against each other, in addition to the SRDF's disabled pairs.
    # The hand-held object's body and the fingers never collide with what the fingers hold.
    extra_disabled_collisions: list[list[str]] = dc.field(
        default_factory=lambda: [
            ["panda_attachment", "panda_leftfinger"],
            ["panda_attachment", "panda_rightfinger"],
        ]
    )
    # Joint-space step for edge collision checks, rad.
    edge_step_size: float = 0.05
    # Padding added to robot-environment and robot-robot distances, m.
    env_collision_padding: float = 0.0
    self_collision_padding: float = 0.0
    # How far a held object may sink into world objects, m: a grasped object still resting on
    # the table, or set down on it, touches it (MoveIt allows this with ACM / touch links).
    held_object_touch_tolerance: float = 0.002
