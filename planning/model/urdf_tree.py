"""The kinematic tree of a URDF: links, joints, their limits and how they connect; no Drake.

``read_urdf_tree`` reads URDF text (already rendered, if it came from xacro) into a ``UrdfTree``,
checking what urdfdom checks: one ``robot`` element with a name, unique link and joint names, a
known joint type, a parent and a child that are links of the file, at most one parent joint per
link, one root link and no cycle, ``<limit>`` on revolute and prismatic joints, finite numbers.
Only the ``link`` and ``joint`` elements directly under ``robot`` count (a ``transmission`` or a
``gazebo`` block may name joints too). Anything else (origins, axes, geometry) is Drake's to read.

The tree gives MoveIt's joint order: ``depth_first_joints`` visits the tree from the root link,
the child joints of each link sorted by name, as MoveIt's ``RobotModel`` does over urdfdom's tree
(urdfdom keeps joints in a name-sorted map and attaches them to their parent links in that
order). A group's joints come in that order (``planning.model.srdf.group_joint_names``).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

from drake_sim.base.errors import ConfigError

_log = logging.getLogger(__name__)
JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")


@dataclass(frozen=True)
class UrdfJoint:
    """One URDF joint.

    Attributes:
        name, type: the joint's name and one of ``JOINT_TYPES``.
        parent, child: the names of its parent and child links.
        lower, upper: position limits (rad or m) of ``<limit>``; None when it has none
            (continuous, fixed, floating, planar joints).
        velocity, effort: ``<limit>``'s velocity (rad/s or m/s) and effort (N m or N); None
            when absent.
        mimic: the joint this one follows (``<mimic joint=...>``), or None; its position is
            ``mimic_multiplier * q[mimic] + mimic_offset``.
        soft_lower, soft_upper: ``<safety_controller>``'s soft limits, None when absent. MoveIt
            plans within ``[max(lower, soft_lower), min(upper, soft_upper)]``.
    """

    name: str
    type: str
    parent: str
    child: str
    lower: float | None = None
    upper: float | None = None
    velocity: float | None = None
    effort: float | None = None
    mimic: str | None = None
    mimic_multiplier: float = 1.0
    mimic_offset: float = 0.0
    soft_lower: float | None = None
    soft_upper: float | None = None

    @property
    def is_actuated(self) -> bool:
        """True for a joint with its own position: not fixed and not a mimic joint."""
        return self.type != "fixed" and self.mimic is None


@dataclass
class UrdfTree:
    """The links and joints of one URDF, as a tree.

    Attributes:
        robot_name: ``<robot name=...>``.
        links: link names in file order.
        joints: joint name -> ``UrdfJoint``, in file order.
        where: the file (or other source) the tree came from, named in error messages.
    """

    robot_name: str
    links: list[str]
    joints: dict[str, UrdfJoint]
    where: str = "URDF"
    _parent: dict[str, UrdfJoint] = field(init=False, repr=False, compare=False)
    _link_set: set[str] = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        self._parent = {joint.child: joint for joint in self.joints.values()}
        self._link_set = set(self.links)

    @property
    def root_link(self) -> str:
        """The one link without a parent joint."""
        return next(link for link in self.links if link not in self._parent)

    def parent_joint(self, link: str) -> UrdfJoint | None:
        """Returns the joint whose child is ``link``; None for the root link.

        Raises:
            ConfigError: ``link`` is not a link of the URDF.
        """
        self._check_link(link)
        return self._parent.get(link)

    def chain(self, base_link: str, tip_link: str) -> list[str]:
        """Returns the joints from ``base_link`` down to ``tip_link``, base first.

        Raises:
            ConfigError: either link is unknown, or ``base_link`` is not ``tip_link`` or one of
                its ancestors (no path down the tree from base to tip).
        """
        self._check_link(base_link)
        self._check_link(tip_link)
        names, link = [], tip_link
        while link != base_link:
            joint = self._parent.get(link)
            if joint is None:
                raise ConfigError(
                    f"{self.where}: no chain from {base_link!r} to {tip_link!r}: "
                    f"{base_link!r} is not an ancestor of {tip_link!r}"
                )
            names.append(joint.name)
            link = joint.parent
        return names[::-1]

    def path(self, link_a: str, link_b: str) -> list[str]:
        """Returns the joints between two links: up from ``link_a`` to their lowest common
        ancestor, then down to ``link_b``. An SRDF chain is read this way (MoveIt allows a chain
        "from one end effector to another", through the root).

        Raises:
            ConfigError: either link is unknown.
        """
        self._check_link(link_a)
        self._check_link(link_b)
        ancestors, link = [link_a], link_a
        while link in self._parent:
            link = self._parent[link].parent
            ancestors.append(link)
        down, link = [], link_b
        while link not in ancestors:
            down.append(self._parent[link].name)
            link = self._parent[link].parent
        up = [self._parent[a].name for a in ancestors[: ancestors.index(link)]]
        return up + down[::-1]

    def child_joints(self, link: str) -> list[UrdfJoint]:
        """Returns the joints whose parent is ``link``, sorted by name (urdfdom's order)."""
        self._check_link(link)
        return sorted((j for j in self.joints.values() if j.parent == link), key=lambda j: j.name)

    def depth_first_joints(self) -> list[str]:
        """Returns every joint name in MoveIt's model order (depth first, children by name)."""
        children: dict[str, list[UrdfJoint]] = {}
        for joint in sorted(self.joints.values(), key=lambda j: j.name):
            children.setdefault(joint.parent, []).append(joint)
        order, stack = [], list(reversed(children.get(self.root_link, [])))
        while stack:
            joint = stack.pop()
            order.append(joint.name)
            stack.extend(reversed(children.get(joint.child, [])))
        return order

    def _check_link(self, link: str) -> None:
        if link not in self._link_set:
            raise ConfigError(f"{self.where}: no link {link!r} in robot {self.robot_name!r}")


def parse_xml(text: str, where: str, root_tag: str = "robot") -> ET.Element:
    """Parses XML text whose root element is ``root_tag``.

    Raises:
        ConfigError: naming ``where`` and the position, for text that is not XML or another root.
    """
    try:
        root = ET.fromstring(text)
    except ET.ParseError as e:
        raise ConfigError(f"{where}: not XML ({e})") from None
    if root.tag != root_tag:
        raise ConfigError(f"{where}: the root element is <{root.tag}>, expected <{root_tag}>")
    return root


def xml_number(element: ET.Element, key: str, where: str, default: float | None = None):
    """Returns the finite float of attribute ``key``, or ``default`` when it is absent.

    Raises:
        ConfigError: naming ``where``, the element and the attribute, for a value that is not a
            finite number.
    """
    text = element.get(key)
    if text is None:
        return default
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise ConfigError(f"{where}: <{element.tag}> {key}={text!r} is not a finite number")
    return value


def required(element: ET.Element, key: str, where: str) -> str:
    """Returns the non-empty attribute ``key`` of ``element``.

    Raises:
        ConfigError: naming ``where`` and the element when it is missing or empty.
    """
    value = element.get(key)
    if not value:
        name = element.get("name")
        which = f"<{element.tag} name={name!r}>" if name and key != "name" else f"<{element.tag}>"
        raise ConfigError(f"{where}: {which} has no {key!r} attribute")
    return value


def read_urdf_tree(text: str, where: str) -> UrdfTree:
    """Reads the kinematic tree of URDF text.

    Args:
        text: the URDF (rendered already when it came from xacro).
        where: names the source in messages (usually the file's path).

    Raises:
        ConfigError: naming ``where`` and the element, for text that is not a URDF tree.
    """
    root = parse_xml(text, where)
    robot_name = required(root, "name", where)
    links = [required(element, "name", where) for element in root.findall("link")]
    link_set: set[str] = set()
    for name in links:
        if name in link_set:
            raise ConfigError(f"{where}: link {name!r} is defined twice")
        link_set.add(name)
    if not links:
        raise ConfigError(f"{where}: robot {robot_name!r} has no links")
    joints: dict[str, UrdfJoint] = {}
    for element in root.findall("joint"):
        joint = _read_joint(element, where, link_set)
        if joint.name in joints:
            raise ConfigError(f"{where}: joint {joint.name!r} is defined twice")
        joints[joint.name] = joint
    _check_tree(links, joints, where)
    unknown = [j for j in joints.values() if j.mimic is not None and j.mimic not in joints]
    if unknown:  # MoveIt logs an error and keeps such a joint as an ordinary one
        _log.warning(
            "%s: joints mimicking unknown joints, kept as independent joints: %s",
            where,
            ", ".join(f"{j.name} (mimics {j.mimic})" for j in unknown),
        )
        for joint in unknown:
            joints[joint.name] = dataclasses.replace(joint, mimic=None)
    return UrdfTree(robot_name, links, joints, where)


def _read_joint(element: ET.Element, where: str, links: set[str]) -> UrdfJoint:
    name = required(element, "name", where)
    at = f"{where}: joint {name!r}"
    kind = required(element, "type", where)
    if kind not in JOINT_TYPES:
        raise ConfigError(f"{at}: unknown type {kind!r} (one of {', '.join(JOINT_TYPES)})")
    ends = {}
    for end in ("parent", "child"):
        tag = element.find(end)
        if tag is None:
            raise ConfigError(f"{at}: no <{end}> element")
        ends[end] = required(tag, "link", at)
        if ends[end] not in links:
            raise ConfigError(f"{at}: its {end} link {ends[end]!r} is not a link of the URDF")
    values: dict = {}
    limit = element.find("limit")
    if limit is None and kind in ("revolute", "prismatic"):
        raise ConfigError(f"{at}: a {kind} joint needs a <limit> element")
    if limit is not None:
        for key in ("lower", "upper", "velocity", "effort"):
            values[key] = xml_number(limit, key, at)
        if kind in ("revolute", "prismatic"):  # urdfdom's defaults
            values["lower"] = values["lower"] if values["lower"] is not None else 0.0
            values["upper"] = values["upper"] if values["upper"] is not None else 0.0
        else:  # continuous and the rest have no position limits
            values["lower"] = values["upper"] = None
        if values["lower"] is not None and values["lower"] > values["upper"]:
            raise ConfigError(f"{at}: <limit> lower {values['lower']} > upper {values['upper']}")
        if values["velocity"] is not None and values["velocity"] < 0:
            raise ConfigError(f"{at}: <limit> velocity {values['velocity']} is negative")
    mimic = element.find("mimic")
    if mimic is not None:
        values["mimic"] = required(mimic, "joint", at)
        values["mimic_multiplier"] = xml_number(mimic, "multiplier", at, 1.0)
        values["mimic_offset"] = xml_number(mimic, "offset", at, 0.0)
    safety = element.find("safety_controller")
    if safety is not None:
        values["soft_lower"] = xml_number(safety, "soft_lower_limit", at)
        values["soft_upper"] = xml_number(safety, "soft_upper_limit", at)
    return UrdfJoint(name, kind, ends["parent"], ends["child"], **values)


def _check_tree(links: list[str], joints: dict[str, UrdfJoint], where: str) -> None:
    parent: dict[str, str] = {}
    for joint in joints.values():
        if joint.child in parent:
            raise ConfigError(
                f"{where}: link {joint.child!r} is the child of two joints, "
                f"{parent[joint.child]!r} and {joint.name!r}"
            )
        parent[joint.child] = joint.name
    roots = [link for link in links if link not in parent]
    if len(roots) != 1:
        which = ", ".join(map(repr, roots)) if roots else "none (a cycle)"
        raise ConfigError(f"{where}: a URDF tree has one root link, found {which}")
    by_child = {joint.child: joint for joint in joints.values()}
    for link in links:  # every link must reach the root without a cycle
        seen = set()
        while link in by_child:
            if link in seen:
                raise ConfigError(f"{where}: the joints form a cycle through link {link!r}")
            seen.add(link)
            link = by_child[link].parent
