"""MoveIt's SRDF: planning groups, named states, end effectors, disabled collision pairs.

``parse_srdf`` reads SRDF text as srdfdom does: ``group`` (its ``link``, ``joint``, ``chain`` and
sub-``group`` elements), ``group_state``, ``end_effector``, ``virtual_joint``,
``disable_collisions`` and ``passive_joint``. What it does not use is listed on one warning line:
other elements (``link_sphere_approximation``, ``enable_collisions``, Pinocchio's
``rotor_params``, ...), a ``passive_joint`` inside a group and a ``group_state`` without a
``group`` attribute (srdfdom skips these two as well). Malformed text is a ``ConfigError``
naming the file and the element: not XML, a missing attribute, a value that is not a finite
number, a group or state defined twice, a state, end effector or subgroup naming an unknown
group, subgroups that contain themselves.

Names are checked against the URDF by ``group_joint_names`` and ``srdf_check.check_srdf``.
``group_joint_names`` gives a group's joints as MoveIt's ``JointModelGroup`` does: the joints of
its chains (base to tip, or through their common ancestor when the base is not above the tip),
its joints, the parent joints of its links and those of its subgroups; of these the active ones
(not fixed, not mimic, not passive), in the URDF's depth-first order
(``UrdfTree.depth_first_joints``), not the SRDF's: Baxter's ``both_arms`` lists ``right_arm``
first, yet MoveIt (and MotionBenchMaker's requests) order it left arm first. Virtual joints are
not URDF joints and never appear in that list. ``srdf_check.check_srdf`` checks every group,
state, end effector, virtual and passive joint, and drops, with one warning line, what MoveIt
drops on loading (an element naming something the URDF lacks), keeping the rest.
"""

from __future__ import annotations

import logging
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from drake_sim.base.config import read_text
from drake_sim.base.errors import ConfigError
from drake_sim.robots.files.xacro_files import render_xacro_file
from planning.model.urdf_tree import UrdfTree, parse_xml, required, xml_number

_log = logging.getLogger(__name__)
VIRTUAL_JOINT_TYPES = ("fixed", "floating", "planar")
_USED = {
    "group",
    "group_state",
    "end_effector",
    "virtual_joint",
    "disable_collisions",
    "passive_joint",
}


@dataclass
class SrdfGroup:
    """A planning group as the SRDF lists it (``group_joint_names`` resolves it on a URDF).

    Attributes:
        name: the group's name.
        joints, links: the names of its ``joint`` and ``link`` elements.
        chains: (base link, tip link) of each ``chain``.
        subgroups: the names of its ``group`` elements.
    """

    name: str
    joints: list[str] = field(default_factory=list)
    links: list[str] = field(default_factory=list)
    chains: list[tuple[str, str]] = field(default_factory=list)
    subgroups: list[str] = field(default_factory=list)


@dataclass
class EndEffector:
    """An ``end_effector``: the group that is the effector, attached at ``parent_link``."""

    name: str
    group: str
    parent_link: str
    parent_group: str | None = None


@dataclass
class VirtualJoint:
    """A ``virtual_joint``: how the robot's ``child_link`` attaches to ``parent_frame``
    (``type`` fixed, floating or planar)."""

    name: str
    type: str
    parent_frame: str
    child_link: str


@dataclass
class Srdf:
    """What an SRDF says.

    Attributes:
        robot_name: ``<robot name=...>``.
        groups: group name -> ``SrdfGroup``, in file order.
        group_states: group -> state -> joint -> values (one value per joint variable: rad
            or m), in file order.
        end_effectors, virtual_joints: in file order.
        disabled_collisions: (link1, link2, reason) of each ``disable_collisions``.
        passive_joints: the names of the top-level ``passive_joint`` elements.
        where: the file the SRDF came from, named in error messages.
        dropped: what ``check_srdf`` dropped and why (empty before it).
    """

    robot_name: str
    groups: dict[str, SrdfGroup] = field(default_factory=dict)
    group_states: dict[str, dict[str, dict[str, list[float]]]] = field(default_factory=dict)
    end_effectors: list[EndEffector] = field(default_factory=list)
    disabled_collisions: list[tuple[str, str, str]] = field(default_factory=list)
    virtual_joints: list[VirtualJoint] = field(default_factory=list)
    passive_joints: list[str] = field(default_factory=list)
    where: str = "SRDF"
    dropped: list[str] = field(default_factory=list)


def load_srdf(
    path: Path | str,
    *,
    xacro_args: Mapping[str, object] | None = None,
    package_paths: Mapping[str, Path | str] | None = None,
) -> Srdf:
    """Reads an SRDF file; a ``.xacro`` file is rendered first (see ``render_xacro_file``).

    Raises:
        ConfigError: naming the file, for a missing or malformed file.
    """
    path = Path(path)
    if path.suffix == ".xacro":
        text = render_xacro_file(path, xacro_args=xacro_args, package_paths=package_paths).text
    else:
        text = read_text(path, "SRDF file")
    return parse_srdf(text, str(path))


def parse_srdf(text: str, where: str) -> Srdf:
    """Reads SRDF text (see the module docstring for what is read and checked).

    Raises:
        ConfigError: naming ``where`` and the element, for malformed text.
    """
    root = parse_xml(text, where)
    srdf = Srdf(required(root, "name", where), where=where)
    ignored = sorted({child.tag for child in root if child.tag not in _USED})
    for element in root.findall("group"):
        group = _read_group(element, where, ignored)
        if group.name in srdf.groups:
            raise ConfigError(f"{where}: group {group.name!r} is defined twice")
        srdf.groups[group.name] = group
    for element in root.findall("group_state"):
        if element.get("group"):
            _read_state(element, srdf)
        else:  # srdfdom skips these with an error (Pinocchio's SRDFs have them)
            ignored.append(f"group_state {element.get('name')!r} (it names no group)")
    for element in root.findall("end_effector"):
        at = f"{where}: end_effector {element.get('name')!r}"
        effector = EndEffector(
            required(element, "name", where),
            _group_name(element, "group", srdf, at),
            required(element, "parent_link", at),
            _group_name(element, "parent_group", srdf, at) if element.get("parent_group") else None,
        )
        srdf.end_effectors.append(effector)
    for element in root.findall("virtual_joint"):
        at = f"{where}: virtual_joint {element.get('name')!r}"
        kind = required(element, "type", at).lower()
        if kind not in VIRTUAL_JOINT_TYPES:
            raise ConfigError(f"{at}: type {kind!r} is not one of {', '.join(VIRTUAL_JOINT_TYPES)}")
        srdf.virtual_joints.append(
            VirtualJoint(
                required(element, "name", where),
                kind,
                required(element, "parent_frame", at),
                required(element, "child_link", at),
            )
        )
    for element in root.findall("disable_collisions"):
        pair = required(element, "link1", where), required(element, "link2", where)
        srdf.disabled_collisions.append((*pair, element.get("reason", "")))
    srdf.passive_joints = [required(e, "name", where) for e in root.findall("passive_joint")]
    for group in srdf.groups.values():
        for name in group.subgroups:
            if name not in srdf.groups:
                raise ConfigError(f"{where}: group {group.name!r} has unknown subgroup {name!r}")
        _check_no_cycle(srdf, group.name, [])
    if ignored:
        _log.warning("%s: SRDF elements not used (ignored): %s", where, ", ".join(ignored))
    return srdf


def default_group(srdf: Srdf) -> str:
    """The group to plan for when none is named: the parent group of the first end effector
    that has one, else the first group (MoveIt's Setup Assistant makes the arm the end
    effector's parent group).

    Raises:
        ConfigError: the SRDF has no groups.
    """
    parents = [e.parent_group for e in srdf.end_effectors if e.parent_group in srdf.groups]
    group = (parents or list(srdf.groups) or [""])[0]
    if not group:
        why = f" (dropped: {srdf.dropped[0]})" if srdf.dropped else ""
        raise ConfigError(f"{srdf.where}: the SRDF has no groups to plan for{why}")
    return group


def group_joint_names(srdf: Srdf, group: str, tree: UrdfTree) -> list[str]:
    """Returns the active joints of ``group``, in MoveIt's order (see the module docstring).

    Raises:
        ConfigError: naming the SRDF file and the group, for an unknown group (with the known
            ones), a joint, link or chain end the URDF lacks (in the group or a subgroup), or
            an active joint with several variables (floating or planar). A group without
            active joints gives an empty list.
    """
    if group not in srdf.groups:
        known = ", ".join(srdf.groups) or "none"
        raise ConfigError(f"{srdf.where}: no group {group!r} (the groups are: {known})")
    members = group_members(srdf, group, tree)
    passive = set(srdf.passive_joints)
    names = []
    for name in tree.depth_first_joints():
        joint = tree.joints[name]
        if name in members and joint.is_actuated and name not in passive:
            if joint.type in ("floating", "planar"):
                raise ConfigError(
                    f"{srdf.where}: group {group!r} has {joint.type} joint {name!r}; "
                    "only one-variable joints can be planned"
                )
            names.append(name)
    return names


def _read_group(element: ET.Element, where: str, ignored: list[str]) -> SrdfGroup:
    group = SrdfGroup(required(element, "name", where))
    at = f"{where}: group {group.name!r}"
    for part in element:
        if part.tag == "link":
            group.links.append(required(part, "name", at))
        elif part.tag == "joint":
            group.joints.append(required(part, "name", at))
        elif part.tag == "chain":
            group.chains.append((required(part, "base_link", at), required(part, "tip_link", at)))
        elif part.tag == "group":
            group.subgroups.append(required(part, "name", at))
        elif f"group/{part.tag}" not in ignored:
            ignored.append(f"group/{part.tag}")
    return group


def _read_state(element: ET.Element, srdf: Srdf) -> None:
    where = srdf.where
    name = required(element, "name", where)
    at = f"{where}: group_state {name!r}"
    group = _group_name(element, "group", srdf, at)
    states = srdf.group_states.setdefault(group, {})
    if name in states:
        raise ConfigError(f"{at}: group {group!r} has two states of this name")
    values: dict[str, list[float]] = {}
    for joint in element.findall("joint"):
        joint_name = required(joint, "name", at)
        text = required(joint, "value", f"{at} joint {joint_name!r}")
        if joint_name in values:
            raise ConfigError(f"{at}: joint {joint_name!r} is given twice")
        values[joint_name] = [_number(word, f"{at} joint {joint_name!r}") for word in text.split()]
    states[name] = values


def _number(text: str, at: str) -> float:
    return xml_number(ET.Element("joint", value=text), "value", at)


def _group_name(element: ET.Element, key: str, srdf: Srdf, at: str) -> str:
    name = required(element, key, at)
    if name not in srdf.groups:
        known = ", ".join(srdf.groups) or "none"
        raise ConfigError(f"{at}: {key} {name!r} is not a group (the groups are: {known})")
    return name


def _check_no_cycle(srdf: Srdf, name: str, path: list[str]) -> None:
    if name in path:
        cycle = " -> ".join([*path[path.index(name) :], name])
        raise ConfigError(f"{srdf.where}: groups contain themselves: {cycle}")
    for sub in srdf.groups[name].subgroups:
        _check_no_cycle(srdf, sub, [*path, name])


def group_members(srdf: Srdf, group: str, tree: UrdfTree) -> set[str]:
    """Every joint of ``group`` (fixed and mimic ones included), as MoveIt collects them."""
    spec = srdf.groups[group]
    at = f"{srdf.where}: group {group!r}"
    members: set[str] = set()
    for base, tip in spec.chains:
        try:
            members.update(tree.path(base, tip))
        except ConfigError as e:
            raise ConfigError(f"{at}: chain {base!r} -> {tip!r}: {e}") from None
    for name in spec.joints:
        if name not in tree.joints:
            raise ConfigError(f"{at}: joint {name!r} is not in the URDF ({tree.where})")
        members.add(name)
    links = set(tree.links)
    for link in spec.links:
        if link not in links:
            raise ConfigError(f"{at}: link {link!r} is not in the URDF ({tree.where})")
        parent = tree.parent_joint(link)
        if parent is not None:
            members.add(parent.name)
    for sub in spec.subgroups:
        members |= group_members(srdf, sub, tree)
    return members
