"""A robot as MoveIt sees it, read from its files: the planning group, its limits and named
states, its disabled collision pairs and tips, and the plant Drake builds from its URDF.

``load_robot_model`` takes a description YAML or a ``*_moveit_config`` folder
(``planning.model.description``), reads the URDF's tree (``urdf_tree``) and the SRDF (``srdf``,
checked against the tree as MoveIt checks it) and gathers, over the group's active joints in
MoveIt's order:

* position limits: the URDF's (narrowed to ``safety_controller``'s soft limits, as MoveIt does),
  replaced by ``joint_limits.yaml``'s ``min_position``/``max_position`` where it sets them; a
  continuous joint gets MoveIt's bounds ``[-pi, pi]`` (its positions wrap, ``continuous``);
* velocity limits: the URDF's, replaced by ``joint_limits.yaml``'s where it sets them;
* acceleration and jerk limits: ``joint_limits.yaml``'s; ``inf`` where nothing bounds them (a
  URDF has none);
* the group's named states (SRDF ``group_state``, then the description's ``named_states``,
  which replace states of the same name), as arrays in the group's joint order;
* the end-effector frame and the link held objects hang on (the description's, else the group's
  first tip link), and the positions of the joints outside the group (the description's
  ``default_positions``, else 0 moved into the joint's limits).

``RobotModel.add_to(plant)`` parses the Drake-ready URDF (``robot_files.drake_urdf``: meshes
converted once into the cache) and welds the root link to the world. MoveIt fixes the root with
the SRDF's virtual joint; a ``fixed`` one, or none, is a weld here too. A ``floating`` or
``planar`` virtual joint (a mobile base: Baxter's SRDF declares one) is also welded, at the world
origin: planning moves the group's joints, never the base, so the plant keeps the base where a
MoveIt planning scene keeps it unless a start state moves it. Drake's parser warnings about what
planning does not use (inertias it finds unphysical, mimic tags it ignores, joint friction) are
logged at debug level by this module instead of printed; every other warning shows, and errors
raise.
"""

from __future__ import annotations

import contextlib
import logging
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drake_sim.base.errors import ConfigError
from drake_sim.robots.files import robot_files
from planning.model.description import RobotDescription, load_robot_description
from planning.model.joint_limits import load_joint_limits
from planning.model.srdf import Srdf, default_group, group_joint_names, parse_srdf
from planning.model.srdf_check import check_srdf
from planning.model.urdf_tree import UrdfTree, read_urdf_tree

_log = logging.getLogger(__name__)
_DRAKE_NOISE = re.compile(r"inertia|mimic element|'friction' attribute", re.IGNORECASE)
"""Drake parser warnings that do not matter to planning (logged at debug level)."""


@dataclass
class RobotModel:
    """One robot's planning group and what planning needs of it.

    Attributes:
        name: the URDF's robot name.
        description: the files it came from.
        srdf: the SRDF, checked against the URDF (what MoveIt drops is dropped).
        tree: the URDF's kinematic tree.
        group: the planning group.
        joint_names: the group's active joints, in MoveIt's order.
        lower, upper: position limits (rad or m) over ``joint_names``.
        velocity, acceleration, jerk: speed (rad/s or m/s), acceleration and jerk limits over
            ``joint_names``; ``inf`` where none is set.
        continuous: True for the continuous joints (bounds ``[-pi, pi]``, positions wrap).
        named_states: the group's SRDF states, name -> positions over ``joint_names``.
        tip_links: the group's tips: the parent links of the SRDF end effectors on the group or
            its subgroups, else the tips of its chains, else the last links of its joints
            (two for a two-arm group).
        disabled_pairs: link pairs whose collisions are never checked (SRDF).
        ee_frame: the frame pose goals and ``RobotState`` use (a link of the URDF).
        attach_link: the link held objects hang on.
        default_positions: joint name -> position of every moving joint outside the group.
        urdf_text: the URDF as read (xacro rendered).
    """

    name: str
    description: RobotDescription
    srdf: Srdf
    tree: UrdfTree
    group: str
    joint_names: list[str]
    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray
    continuous: np.ndarray
    named_states: dict[str, np.ndarray]
    tip_links: list[str]
    disabled_pairs: list[tuple[str, str]]
    ee_frame: str = ""
    attach_link: str = ""
    default_positions: dict[str, float] = field(default_factory=dict)
    urdf_text: str = field(default="", repr=False)

    @property
    def num_joints(self) -> int:
        """The number of joints in the group."""
        return len(self.joint_names)

    @property
    def tip_link(self) -> str:
        """The group's first tip (its end-effector link for a one-arm group)."""
        return self.tip_links[0]

    @property
    def root_link(self) -> str:
        """The URDF's root link."""
        return self.tree.root_link

    def drake_urdf(self) -> Path:
        """The Drake-ready URDF in the cache (``robot_files.drake_urdf``), made on first use."""
        return robot_files.drake_urdf(self.description, self.urdf_text or None)

    def add_to(self, plant, *, model_name_prefix: str | None = None):
        """Parses the robot into ``plant`` and welds its root link to the world origin (see the
        module docstring for virtual joints).

        Args:
            plant: an unfinalised ``MultibodyPlant`` (registered with a SceneGraph to have
                geometry).
            model_name_prefix: a prefix for the model instance's name (``prefix::name``), to
                add the same robot twice; the URDF's robot name alone when None.

        Returns:
            The robot's ``ModelInstanceIndex``.

        Raises:
            ConfigError: the files cannot be made Drake-ready.
            RuntimeError: Drake's parser refuses the URDF (its message names the line).
        """
        from pydrake.math import RigidTransform
        from pydrake.multibody.parsing import Parser

        urdf = self.drake_urdf()
        prefix = model_name_prefix
        parser = Parser(plant) if prefix is None else Parser(plant, prefix)
        with _drake_noise_to_debug():
            (instance,) = parser.AddModels(str(urdf))
        if self.root_link != "world":
            root = plant.GetFrameByName(self.root_link, instance)
            plant.WeldFrames(plant.world_frame(), root, RigidTransform())
        return instance


def load_robot_model(
    source: RobotDescription | Path | str, *, group: str | None = None
) -> RobotModel:
    """Reads a robot model from a description YAML, a MoveIt config folder or a description.

    Args:
        source: the YAML, the ``*_moveit_config`` folder, or a ``RobotDescription``.
        group: the planning group, replacing the description's.

    Raises:
        ConfigError: naming the file: a missing file or package, a malformed URDF, SRDF or
            limits file, an unknown group (the known ones named), a name the URDF lacks.
    """
    if isinstance(source, RobotDescription):
        description = source
    else:
        description = load_robot_description(source, group=group)
    group = group or description.group
    packages = robot_files.package_map(description)
    base = robot_files.description_base(description)
    urdf_path = robot_files.urdf_file(description)
    text = robot_files.read_robot_file(urdf_path, packages, description.xacro_args)
    tree = read_urdf_tree(text, str(urdf_path))
    robot_files.mesh_files(description, text)  # a missing mesh fails here, not in add_to
    srdf_path = robot_files.resolve_uri(description.srdf, base, packages)
    srdf_text = robot_files.read_robot_file(srdf_path, packages, description.xacro_args)
    srdf = check_srdf(parse_srdf(srdf_text, str(srdf_path)), tree)
    group = group or default_group(srdf)
    if group not in srdf.groups:
        why = [d for d in srdf.dropped if d.startswith(f"group {group!r}")]
        if why:
            raise ConfigError(f"{srdf_path}: the planning {why[0]}")
    names = group_joint_names(srdf, group, tree)
    if not names:
        raise ConfigError(f"{srdf_path}: group {group!r} has no active joints to plan for")
    limits = _limits(tree, names)
    if description.joint_limits:
        path = robot_files.resolve_uri(description.joint_limits, base, packages)
        _apply_joint_limits(limits, names, load_joint_limits(path), tree, str(path))
    tips = _tip_links(srdf, group, tree, names)
    where = description.source or "robot description"
    for key in ("ee_frame", "attach_link"):
        link = getattr(description, key)
        if link and link not in tree.links:
            raise ConfigError(f"{where}: {key}: the URDF has no link {link!r}")
    named = _named_states(srdf, group, names, limits)
    for state, q in description.named_states.items():
        if len(q) != len(names):
            raise ConfigError(
                f"{where}: named_states.{state} has {len(q)} values, group {group!r} has "
                f"{len(names)} joints ({', '.join(names)})"
            )
        named[state] = np.array(q, dtype=float)
    return RobotModel(
        name=tree.robot_name,
        description=description,
        srdf=srdf,
        tree=tree,
        group=group,
        joint_names=names,
        named_states=named,
        tip_links=tips,
        disabled_pairs=[(a, b) for a, b, _ in srdf.disabled_collisions],
        ee_frame=description.ee_frame or tips[0],
        attach_link=description.attach_link or tips[0],
        default_positions=_default_positions(tree, names, description, where),
        urdf_text=text,
        **limits,
    )


def _default_positions(tree: UrdfTree, names: list[str], description, where: str) -> dict:
    """Positions of the moving joints outside the group: the description's, else 0 moved into
    the joint's limits (mimic joints follow their leader in Drake's plant too: kept here)."""
    moving = [j for j in tree.joints.values() if j.type not in ("fixed", "floating", "planar")]
    outside = {j.name: j for j in moving if j.name not in names}
    unknown = [n for n in description.default_positions if n not in outside]
    if unknown:
        raise ConfigError(
            f"{where}: default_positions: {', '.join(unknown)} not moving joints outside the group"
        )
    positions = {}
    for name, joint in outside.items():
        low = joint.lower if joint.lower is not None and joint.type != "continuous" else -np.inf
        high = joint.upper if joint.upper is not None and joint.type != "continuous" else np.inf
        if name in description.default_positions:
            value = description.default_positions[name]
            if not low - 1e-9 <= value <= high + 1e-9:
                raise ConfigError(
                    f"{where}: default_positions.{name} = {value:g} is outside the joint's "
                    f"limits [{low:g}, {high:g}]"
                )
        else:
            value = min(max(0.0, low), high)
        positions[name] = float(value)
    return positions


def _limits(tree: UrdfTree, names: list[str]) -> dict[str, np.ndarray]:
    """The URDF's limits over ``names`` (MoveIt's rules, see the module docstring)."""
    n = len(names)
    out = {key: np.full(n, np.inf) for key in ("upper", "velocity", "acceleration", "jerk")}
    out["lower"], out["continuous"] = np.full(n, -np.inf), np.zeros(n, dtype=bool)
    for i, name in enumerate(names):
        joint = tree.joints[name]
        if joint.type == "continuous":
            out["lower"][i], out["upper"][i], out["continuous"][i] = -math.pi, math.pi, True
        else:
            lower = joint.lower if joint.soft_lower is None else max(joint.lower, joint.soft_lower)
            upper = joint.upper if joint.soft_upper is None else min(joint.upper, joint.soft_upper)
            out["lower"][i], out["upper"][i] = lower, upper
        if joint.velocity:  # urdfdom: a velocity of 0 means unbounded
            out["velocity"][i] = joint.velocity
    return out


def _apply_joint_limits(limits, names, table, tree, where: str) -> None:
    """Replaces the URDF's limits by ``joint_limits.yaml``'s where its flags set them."""
    index = {name: i for i, name in enumerate(names)}
    outside = [name for name in table if name not in tree.joints]
    if outside:
        _log.warning("%s: joints not in the URDF (ignored): %s", where, ", ".join(outside))
    for name, limit in table.items():
        i = index.get(name)
        if i is None:
            continue
        if limit.has_position_limits:
            limits["lower"][i], limits["upper"][i] = limit.min_position, limit.max_position
            limits["continuous"][i] = False
        for key, flag, value in (
            ("velocity", limit.has_velocity_limits, limit.max_velocity),
            ("acceleration", limit.has_acceleration_limits, limit.max_acceleration),
            ("jerk", limit.has_jerk_limits, limit.max_jerk),
        ):
            if flag:
                limits[key][i] = value


def _named_states(srdf: Srdf, group: str, names: list[str], limits: dict) -> dict:
    """The group's states as arrays over ``names``. A state that leaves a joint out is dropped
    (it is no whole configuration of the group); one outside the limits is kept (MoveIt keeps
    it too); each is named on one warning line."""
    states, partial, outside = {}, [], []
    for state, values in srdf.group_states.get(group, {}).items():
        if not all(name in values for name in names):
            partial.append(state)
            continue
        q = states[state] = np.array([values[name][0] for name in names], dtype=float)
        low, high = limits["lower"], limits["upper"]
        beyond = [f"{n} {q[i]:g}" for i, n in enumerate(names) if not low[i] <= q[i] <= high[i]]
        if beyond:
            outside.append(f"{state} ({', '.join(beyond)})")
    at = f"{srdf.where}: group {group!r}"
    if partial:
        _log.warning("%s: states that leave out joints (ignored): %s", at, ", ".join(partial))
    if outside:
        _log.warning("%s: states outside the joint limits: %s", at, "; ".join(outside))
    return states


def _tip_links(srdf: Srdf, group: str, tree: UrdfTree, names: list[str]) -> list[str]:
    """The group's tips (see ``RobotModel.tip_links``)."""
    groups = _with_subgroups(srdf, group)
    links = _group_links(tree, names)
    tips = []
    for effector in srdf.end_effectors:
        attached = (
            effector.parent_group in groups
            if effector.parent_group
            else effector.parent_link in links
        )
        if attached and effector.parent_link not in tips:
            tips.append(effector.parent_link)
    if not tips:
        tips = [tip for name in groups for _, tip in srdf.groups[name].chains]
    if not tips:
        below = {j.child: j for j in tree.joints.values()}
        ancestors = set()
        for name in names:
            link = tree.joints[name].parent
            while link in below:
                ancestors.add(below[link].name)
                link = below[link].parent
        tips = [tree.joints[name].child for name in names if name not in ancestors]
    return list(dict.fromkeys(tips))


def _with_subgroups(srdf: Srdf, group: str) -> list[str]:
    found = [group]
    for sub in srdf.groups[group].subgroups:
        found += [name for name in _with_subgroups(srdf, sub) if name not in found]
    return found


def _group_links(tree: UrdfTree, names: list[str]) -> set[str]:
    """The child links of the group's joints and the links fixed to them."""
    links, stack = set(), [tree.joints[name].child for name in names]
    while stack:
        link = stack.pop()
        links.add(link)
        stack += [j.child for j in tree.child_joints(link) if j.type == "fixed"]
    return links


@contextlib.contextmanager
def _drake_noise_to_debug():
    """Within the block, Drake's warnings matching ``_DRAKE_NOISE`` go to this module's debug
    log instead of the ``drake`` logger's handlers."""

    def keep(record: logging.LogRecord) -> bool:
        if record.levelno <= logging.WARNING and _DRAKE_NOISE.search(record.getMessage()):
            _log.debug("drake: %s", record.getMessage())
            return False
        return True

    logger = logging.getLogger("drake")
    logger.addFilter(keep)
    try:
        yield
    finally:
        logger.removeFilter(keep)
