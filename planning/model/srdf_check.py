"""An SRDF checked against its URDF, as MoveIt keeps it: ``check_srdf`` drops what names
something the URDF lacks (one warning line says what and why) and keeps the rest."""

from __future__ import annotations

import dataclasses
import logging

from drake_sim.base.errors import ConfigError
from planning.model.srdf import Srdf, group_joint_names, group_members
from planning.model.urdf_tree import UrdfTree

_log = logging.getLogger(__name__)


def check_srdf(srdf: Srdf, tree: UrdfTree, *, strict: bool = False) -> Srdf:
    """Checks the names an SRDF uses against the URDF ``tree``; returns the SRDF as MoveIt keeps
    it on that URDF.

    MoveIt drops what it cannot use with an error message and loads the rest, and so does this,
    with one warning line listing what was dropped and why: a group naming a joint, link or
    chain end the URDF lacks (and the groups, states and end effectors built on it), a group
    state naming such a joint or giving the wrong number of values, an end effector's parent
    link, a virtual joint's child link or a passive joint that the URDF lacks, a disabled pair
    naming an unknown link (real SRDFs have them: VAMP's Fetch names ``bellows_link2``), and a
    group state's value for a fixed joint or a joint outside the group. ``strict`` raises the
    first of these instead (the pairs and the unused state values are always only dropped).

    Returns:
        A copy of ``srdf`` without what was dropped (``dropped``: the reasons, by element).

    Raises:
        ConfigError: with ``strict``, naming the SRDF file and the element.
    """
    where, dropped = srdf.where, []

    def drop(error: ConfigError) -> None:
        if strict:
            raise error
        dropped.append(str(error).removeprefix(f"{where}: "))

    groups = dict(srdf.groups)
    changed = True
    while changed:  # a group built on a dropped group is dropped too
        changed = False
        for name in list(groups):
            gone = [sub for sub in groups[name].subgroups if sub not in groups]
            try:
                if gone:
                    raise ConfigError(
                        f"{where}: group {name!r}: its subgroup {gone[0]!r} is dropped"
                    )
                group_joint_names(dataclasses.replace(srdf, groups=groups), name, tree)
            except ConfigError as e:
                drop(e)
                del groups[name]
                changed = True
    kept = dataclasses.replace(srdf, groups=groups)
    states = {
        group: _checked_states(kept, group, tree, dropped, drop)
        for group in srdf.group_states
        if group in groups
    }
    links = set(tree.links)
    end_effectors = []
    for e in srdf.end_effectors:
        if e.parent_link not in links:
            drop(
                ConfigError(
                    f"{where}: end_effector {e.name!r} parent_link {e.parent_link!r} "
                    f"is not a link of the URDF ({tree.where})"
                )
            )
        elif e.group not in groups:
            drop(ConfigError(f"{where}: end_effector {e.name!r}: its group {e.group!r} is dropped"))
        else:
            end_effectors.append(e)
    virtual_joints = []
    for v in srdf.virtual_joints:
        if v.child_link in links:
            virtual_joints.append(v)
        else:
            drop(
                ConfigError(
                    f"{where}: virtual_joint {v.name!r} child_link {v.child_link!r} "
                    f"is not a link of the URDF ({tree.where})"
                )
            )
    virtual = {v.name for v in virtual_joints}
    passive = []
    for name in srdf.passive_joints:
        if name in tree.joints or name in virtual:
            passive.append(name)
        else:
            drop(ConfigError(f"{where}: passive_joint {name!r} is not in the URDF ({tree.where})"))
    pairs = [p for p in srdf.disabled_collisions if p[0] in links and p[1] in links]
    if len(pairs) < len(srdf.disabled_collisions):
        unknown = {n for p in srdf.disabled_collisions for n in p[:2] if n not in links}
        dropped.append(
            f"{len(srdf.disabled_collisions) - len(pairs)} disable_collisions pairs naming "
            f"links {', '.join(sorted(unknown))}"
        )
    if dropped:
        _log.warning("%s: dropped on %s, as MoveIt does: %s", where, tree.where, "; ".join(dropped))
    parts = {"group_states": states, "end_effectors": end_effectors}
    parts |= {"virtual_joints": virtual_joints, "passive_joints": passive}
    return dataclasses.replace(kept, **parts, disabled_collisions=pairs, dropped=dropped)


def _checked_states(srdf: Srdf, group: str, tree: UrdfTree, dropped: list[str], drop) -> dict:
    members, kept = group_members(srdf, group, tree), {}
    for state, values in srdf.group_states[group].items():
        at = f"{srdf.where}: group_state {state!r} of group {group!r}"
        state_values, unused, bad = {}, [], None
        for joint, value in values.items():
            if joint not in tree.joints:
                bad = ConfigError(f"{at}: joint {joint!r} is not in the URDF ({tree.where})")
                break
            kind = tree.joints[joint].type
            if joint not in members or kind == "fixed":
                unused.append(joint)
                continue
            count = {"floating": 7, "planar": 3}.get(kind, 1)
            if len(value) != count:
                bad = ConfigError(f"{at}: joint {joint!r} has {len(value)} values, not {count}")
                break
            state_values[joint] = value
        if bad is not None:
            drop(bad)
            continue
        kept[state] = state_values
        if unused:
            dropped.append(
                f"group_state {state} values of {', '.join(unused)} (fixed or not in {group})"
            )
    return kept
