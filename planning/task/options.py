"""Options of ``PickPlaceTask`` (the ``task`` section of the pick-and-place scenario), in m and s.
No ``from __future__ import annotations``: the YAML loader reads the field types at run time."""

import dataclasses as dc


@dc.dataclass
class PickPlaceOptions:
    """Heights and margins of the task (m)."""

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
