"""Options of ``PickPlaceTask`` (the ``task`` section of the pick-and-place scenario), in m, s and
rad. No ``from __future__ import annotations``: the YAML loader reads the field types at run time.

The task moves a grasp frame G (the TCP): its z axis points along the approach (down at a grasp),
its y axis is the fingers' closing axis and its origin is between the fingertips. ``tool_xyz``
and ``tool_rpy`` give G in the robot's end-effector frame E (``robot.model.ee_frame``): zero for
the Panda, whose ``panda_hand_tcp`` is such a frame; the UR5's scenario puts G between its
Robotiq pads, 0.17 m out along ``tool0``'s z and turned so that y is the pads' axis.
"""

import dataclasses as dc
import math


@dc.dataclass
class PickPlaceOptions:
    """Heights and margins of the task (m), and where its grasp frame is."""

    pregrasp_height: float = 0.12  # TCP above the grasp before going straight down
    grasp_depth: float = 0.03  # TCP below the object's top, at most half the object's height
    finger_clearance: float = 0.012  # TCP at least this far above the table top
    lift_height: float = 0.05  # lift after closing
    preplace_height: float = 0.05  # object above its place height before going straight down
    place_clearance: float = 0.003  # object's bottom above the table when released
    retreat_height: float = 0.10  # TCP rise after release
    max_object_width: float = 0.075  # widest side the open hand (0.08 m) closes across
    min_object_width: float = 0.005
    overlap_margin: float = 0.0  # object boxes closer than this count as overlapping
    place_tolerance: float = 0.02  # largest horizontal place error of a success
    settle_time: float = 0.5  # s of simulated time after release before measuring
    tool_xyz: list[float] = dc.field(default_factory=lambda: [0.0, 0.0, 0.0])  # p_EG, m
    tool_rpy: list[float] = dc.field(default_factory=lambda: [0.0, 0.0, 0.0])  # R_EG, rad

    def check(self, prefix: str = "") -> None:
        """Raises ValueError naming the first value that is out of range (its key after
        ``prefix``)."""
        for field in dc.fields(self):
            value = getattr(self, field.name)
            if isinstance(value, list):
                if len(value) != 3 or not all(math.isfinite(v) for v in value):
                    raise ValueError(f"'{prefix}{field.name}' needs 3 finite values")
            elif not value >= 0.0:
                raise ValueError(f"'{prefix}{field.name}' must be >= 0")
