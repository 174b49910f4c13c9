"""How the robot is loaded for planning, and the table a new scene starts with.

The ``model`` and ``table`` sections of ``planning.config.PlanningConfig`` (the ``robot``
section of the pick-and-place scenario), kept with the model that reads them
(``planning.model.planning_model``). The robot is a description (``description``: the Panda by
default); what is robot-specific (frames, named states, finger positions) comes from it, and
the fields here only change it. Every field has a default; joint positions in rad or m, lengths
in m. No ``from __future__ import annotations``: the YAML loader reads the field types at run
time.
"""

import dataclasses as dc


@dc.dataclass
class TableConfig:
    """A box table in the world frame W, by default under the Panda with its top at z = 0."""

    size: list[float] = dc.field(default_factory=lambda: [1.2, 1.4, 0.04])  # m, full extents
    position: list[float] = dc.field(default_factory=lambda: [0.3, 0.0, -0.02])  # m, p_WT centre


@dc.dataclass
class RobotModelConfig:
    """How the robot is loaded for planning."""

    # The robot: a shipped robot's name (config/robots/<name>.yaml: panda, ur5, fetch, baxter),
    # a robot description YAML or a *_moveit_config folder (planning.model.description).
    description: str = "panda"
    # The planning group; "" for the description's.
    group: str = ""
    # "convex_mesh" (the URDF's collision meshes, checked as their convex hulls) or, for the
    # Panda only, "primitives" (the spheres and cylinders of example-robot-data's
    # panda_collision.urdf).
    collision_geometry: str = "convex_mesh"
    # Frame whose pose RobotState reports and IK targets; "" for the description's (the Panda's
    # is the tool centre point between the fingertips, MoveIt's end effector).
    ee_frame: str = ""
    # Each finger's position (m, the joints below the attach link); None for the description's
    # default positions (the Panda's: 0.04, fully open).
    finger_position: float | None = None
    # More named configurations of the group (rad or m, one value per joint of the group);
    # they replace the description's of the same name.
    named_configurations: dict[str, list[float]] = dc.field(default_factory=dict)
    # Link pairs never checked against each other, in addition to the SRDF's disabled pairs
    # (held objects are never checked against the attach link and the links below it).
    extra_disabled_collisions: list[list[str]] = dc.field(default_factory=list)
    # Joint-space step for edge collision checks, rad.
    edge_step_size: float = 0.05
    # Padding added to robot-environment and robot-robot distances, m.
    env_collision_padding: float = 0.0
    self_collision_padding: float = 0.0
    # How far a held object may sink into world objects, m: a grasped object still resting on
    # the table, or set down on it, touches it (MoveIt allows this with ACM / touch links).
    held_object_touch_tolerance: float = 0.002
