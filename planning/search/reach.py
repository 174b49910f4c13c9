"""A conservative bound on how far a frame of a robot can reach from its first moving joint.

Walking the joints from the root to the frame's body (at any configuration; the zero one is
used), the distance from an anchor point to points beyond it stays the same under every revolute
joint whose axis passes through the anchor (a rotation about an axis through a point keeps the
point, and maps lines through it to lines through it). So the anchor starts at the first moving
joint's origin; each revolute joint whose axis passes through the anchor is skipped; any other
joint's origin becomes the next anchor, adding its distance from the last; a prismatic joint
adds its travel too (``max(|lower|, |upper|)``); the frame's origin ends the chain. The sum bounds
the distance from the first anchor to the frame at every configuration, and is tight for the
Panda (its shoulder, elbow and wrist centres: 0.316, 0.0825 and 0.384 m offsets give the classic
0.33 + 0.39 + 0.088 + flange-to-tool chain).

IK uses it to refuse targets out of reach at once, instead of after its whole time budget.
"""

from __future__ import annotations

import numpy as np

_ON_AXIS = 1e-9  # m: an anchor this close to an axis is on it (larger would not be conservative)


def reach_bound(plant, context, frame) -> tuple[np.ndarray, float]:
    """Returns ``(p_WA, reach)``: the first moving joint's origin A in the world at ``context``
    and a bound on the distance from A to ``frame``'s origin over every configuration of the
    joints between them (the configuration in ``context`` is used to evaluate the geometry)."""
    chain = _moving_chain(plant, frame.body())
    p_E = frame.CalcPoseInWorld(context).translation()
    if not chain:
        return p_E, 0.0
    anchor = chain[0].frame_on_child().CalcPoseInWorld(context).translation()
    reach = 0.0
    for joint in chain[1:]:
        X_WJ = joint.frame_on_child().CalcPoseInWorld(context)
        p = X_WJ.translation()
        if joint.type_name() == "revolute":
            axis = X_WJ.rotation().matrix() @ np.asarray(joint.revolute_axis())
            offset = anchor - p
            if np.linalg.norm(offset - (offset @ axis) * axis) < _ON_AXIS:
                continue
        reach += float(np.linalg.norm(p - anchor))
        anchor = p
        if joint.type_name() == "prismatic":
            travel = np.abs([joint.position_lower_limit(), joint.position_upper_limit()]).max()
            reach += float(travel)
    reach += float(np.linalg.norm(p_E - anchor))
    first = chain[0].frame_on_child().CalcPoseInWorld(context).translation()
    return first, reach


def _moving_chain(plant, body) -> list:
    """The moving joints from the root to ``body``, root first (welds left out)."""
    parent_joint = {}
    for index in plant.GetJointIndices():
        joint = plant.get_joint(index)
        parent_joint[joint.child_body().index()] = joint
    chain = []
    while body.index() != plant.world_body().index() and body.index() in parent_joint:
        joint = parent_joint[body.index()]
        if joint.num_positions() > 0:
            chain.append(joint)
        body = joint.parent_body()
    return chain[::-1]
