"""Where a robot's files are: the robot description YAML, or a MoveIt ``*_moveit_config`` folder.

A description YAML names the files MoveIt would load for a robot::

    urdf: ur5/ur5.urdf                   # a path, package://pkg/path or $(find pkg)/path;
                                         # .xacro is rendered with xacro_args
    srdf: ur5/ur5.srdf                   # the same forms; .srdf.xacro too
    package_paths: {ur_description: ../ur_description}   # for package:// and $(find pkg)
    group: manipulator                   # optional: the planning group (default: the SRDF's
                                         # first end effector's parent group, else first group)
    joint_limits: config/joint_limits.yaml               # optional: MoveIt's limits
    xacro_args: {name: ur5}              # optional: $(arg name) values

and, for planning here (MoveIt keeps these in other files or in code; all optional)::

    ee_frame: tool0                      # the frame RobotState reports and pose goals target
                                         # (default: the group's first tip link)
    attach_link: wrist_3_link            # where held objects hang (default: the tip link);
                                         # they are not checked against it or the links below it
    named_states: {home: [0, -1.57, 0, -1.57, 0, 0]}    # more named states of the group, over
                                         # its joints in MoveIt's order (replacing the SRDF's)
    default_positions: {finger_joint: 0.04}   # positions of joints outside the group (default:
                                         # 0, or the limit nearest to 0)
    collision_meshes: pieces             # hull (default): each collision mesh is checked as
                                         # its convex hull, as Drake does; pieces: cut into
                                         # convex pieces first (drake_sim.robots.files.mesh_pieces),
                                         # nearer the triangles MoveIt's FCL checks

Paths and package folders are relative to the YAML file; URIs (``package://``, ``$(find ...)``)
stay as written, for ``drake_sim.robots.files.robot_files`` to resolve (a package's folder may
be one: ``{ur_description: package://example-robot-data/robots/ur_description}``). A file or
folder given as a path must exist; it is made absolute without following symbolic links, so
files beside it are found where the user put them. A key not listed above is ignored, with one
warning line.

``load_robot_description`` also takes a MoveIt config folder: its package (named in its
``package.xml``) is added to the package map; the URDF is the one its ``.setup_assistant``
names (``package://<package>/<relative_path>``, with the xacro arguments given there), else
the one ``config/*.urdf.xacro`` or ``config/*.urdf``; the SRDF is the one ``.setup_assistant``
names, else the one ``config/*.srdf`` (or ``config/*.srdf.xacro``); the limits are
``config/joint_limits.yaml`` when present; the group, unless given, is the parent group of the
SRDF's first end effector, else its first group.
"""

from __future__ import annotations

import logging
import math
import os
import shlex
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

from drake_sim.base.config import parse_yaml, read_text
from drake_sim.base.errors import ConfigError
from drake_sim.robots.files.xacro_files import xacro_value
from planning.model.srdf import default_group, load_srdf

_log = logging.getLogger(__name__)
_KEYS = (
    "urdf",
    "srdf",
    "package_paths",
    "group",
    "joint_limits",
    "xacro_args",
    "ee_frame",
    "attach_link",
    "named_states",
    "default_positions",
    "collision_meshes",
)
COLLISION_MESHES = ("hull", "pieces")
"""The values of ``collision_meshes``."""


@dataclass
class RobotDescription:
    """The files of one robot and the group to plan for.

    Attributes:
        urdf: the URDF or its xacro: an absolute path or a URI (``package://``, ``$(find)``).
        srdf: the SRDF (or ``.srdf.xacro``), in the same forms.
        package_paths: package name -> absolute folder (or a URI of a folder in a package).
        group: the SRDF group to plan for ("": the default, ``srdf.default_group``).
        joint_limits: MoveIt's ``joint_limits.yaml`` (path or URI); "" for none.
        xacro_args: ``$(arg name)`` values for the URDF's and the SRDF's xacro.
        source: the description YAML or MoveIt config folder this came from.
        ee_frame: the end-effector frame ("": the group's first tip link).
        attach_link: the link held objects hang on ("": the group's first tip link).
        named_states: more named states of the group, name -> positions over its joints.
        default_positions: joint name -> position for joints outside the group.
        collision_meshes: "hull" (each collision mesh checked as its convex hull) or
            "pieces" (cut into convex pieces, each checked as its hull).
    """

    urdf: str
    srdf: str
    package_paths: dict[str, str]
    group: str
    joint_limits: str = ""
    xacro_args: dict[str, str] = field(default_factory=dict)
    source: str = ""
    ee_frame: str = ""
    attach_link: str = ""
    named_states: dict[str, list[float]] = field(default_factory=dict)
    default_positions: dict[str, float] = field(default_factory=dict)
    collision_meshes: str = "hull"


def load_robot_description(
    path: Path | str, *, group: str | None = None, package_paths: dict | None = None
) -> RobotDescription:
    """Reads a robot description YAML or a MoveIt config folder (see the module docstring).

    Args:
        path: the YAML file or the ``*_moveit_config`` folder.
        group: the planning group, replacing the file's.
        package_paths: more package folders (relative to the working directory), replacing
            entries of the same name.

    Raises:
        ConfigError: naming the file and the key: a missing or malformed file, a missing key, a
            value of the wrong type, a path that does not exist.
    """
    path = Path(path)
    extra = {
        str(k): _folder(v, Path.cwd(), f"package_paths.{k}", "package_paths argument")
        for k, v in (package_paths or {}).items()
    }
    if path.is_dir():
        return _from_moveit_config(path, group, extra)
    where = str(path)
    data = parse_yaml(read_text(path, "robot description"), where)
    if not isinstance(data, dict):
        raise ConfigError(f"{where}: a robot description is a mapping with keys {', '.join(_KEYS)}")
    unknown = [str(key) for key in data if key not in _KEYS]
    if unknown:
        _log.warning("%s: keys not used (ignored): %s", where, ", ".join(unknown))
    base = path.parent
    packages = {
        str(k): _folder(v, base, f"package_paths.{k}", where)
        for k, v in _mapping(data, "package_paths", where).items()
    }
    return RobotDescription(
        urdf=_file(_text(data, "urdf", where), base, "urdf", where),
        srdf=_file(_text(data, "srdf", where), base, "srdf", where),
        package_paths={**packages, **extra},
        group=group or (_text(data, "group", where) if "group" in data else ""),
        joint_limits=_file(_text(data, "joint_limits", where, ""), base, "joint_limits", where),
        xacro_args=_xacro_args(_mapping(data, "xacro_args", where), where),
        source=where,
        ee_frame=_text(data, "ee_frame", where, ""),
        attach_link=_text(data, "attach_link", where, ""),
        named_states=_named_states(_mapping(data, "named_states", where), where),
        default_positions=_positions(_mapping(data, "default_positions", where), where),
        collision_meshes=_choice(data, "collision_meshes", COLLISION_MESHES, where),
    )


def is_uri(text: str) -> bool:
    """True for ``package://...``, ``file://...`` and other URIs, and for ``$(find pkg)/...``."""
    return "://" in text or text.startswith("$(")


def _from_moveit_config(folder: Path, group: str | None, extra: dict) -> RobotDescription:
    folder = _absolute(folder)
    packages = {_package_name(folder): str(folder), **extra}
    urdf, srdf, args = _setup_assistant(folder)
    config = folder / "config"
    urdf = urdf or _one(config, ("*.urdf.xacro", "*.urdf"), "URDF", folder)
    srdf = (
        srdf
        or _one(config, ("*.srdf",), "", folder)
        or _one(config, ("*.srdf.xacro",), "SRDF", folder)
    )
    limits = config / "joint_limits.yaml"
    if not group:
        group = default_group(load_srdf(srdf, xacro_args=args, package_paths=packages))
    return RobotDescription(
        urdf=urdf,
        srdf=srdf,
        package_paths=packages,
        group=group,
        joint_limits=str(limits) if limits.is_file() else "",
        xacro_args=args,
        source=str(folder),
    )


def _package_name(folder: Path) -> str:
    manifest = folder / "package.xml"
    if manifest.is_file():
        try:
            name = ET.fromstring(read_text(manifest, "package.xml")).findtext("name")
        except ET.ParseError as e:
            raise ConfigError(f"{manifest}: not XML ({e})") from None
        if name and name.strip():
            return name.strip()
    return folder.name


def _setup_assistant(folder: Path) -> tuple[str, str, dict[str, str]]:
    """The URDF URI, SRDF path and xacro arguments a ``.setup_assistant`` names ("" if none)."""
    setup = folder / ".setup_assistant"
    if not setup.is_file():
        return "", "", {}
    data = parse_yaml(read_text(setup, "setup assistant file"), str(setup))
    config = data.get("moveit_setup_assistant_config") if isinstance(data, dict) else None
    if not isinstance(config, dict):
        raise ConfigError(f"{setup}: no moveit_setup_assistant_config mapping")
    config = {str(k).lower(): v for k, v in config.items()}  # URDF in MoveIt 1, urdf in 2
    urdf_entry = config.get("urdf") if isinstance(config.get("urdf"), dict) else {}
    srdf_entry = config.get("srdf") if isinstance(config.get("srdf"), dict) else {}
    urdf = ""
    if urdf_entry.get("package") and urdf_entry.get("relative_path"):
        urdf = f"package://{urdf_entry['package']}/{urdf_entry['relative_path']}"
    srdf = ""
    if srdf_entry.get("relative_path"):
        srdf = _file(str(srdf_entry["relative_path"]), folder, "SRDF.relative_path", str(setup))
    args = {}
    for word in shlex.split(str(urdf_entry.get("xacro_args") or "")):
        name, sep, value = word.partition(":=")
        if not sep:
            raise ConfigError(f"{setup}: URDF.xacro_args {word!r} is not name:=value")
        args[name] = value
    return urdf, srdf, args


def _one(config: Path, patterns: tuple[str, ...], what: str, folder: Path) -> str:
    """The one file matching the first pattern that matches; "" when none matches and ``what``
    is empty, else a ``ConfigError``."""
    for pattern in patterns:
        found = sorted(config.glob(pattern))
        if len(found) == 1:
            return str(found[0])
        if found:
            names = ", ".join(p.name for p in found)
            raise ConfigError(
                f"{folder}: several {pattern} files in config/ ({names}); name one in a "
                "robot description YAML"
            )
    if what:
        raise ConfigError(
            f"{folder}: no {what} found (no .setup_assistant naming one, no "
            f"{' or '.join('config/' + p for p in patterns)})"
        )
    return ""


def _text(data: dict, key: str, where: str, default: str | None = None) -> str:
    value = data.get(key, default)
    if value is None:
        raise ConfigError(f"{where}: {key}: missing (a robot description needs {key})")
    if not isinstance(value, str) or (default is None and not value.strip()):
        raise ConfigError(f"{where}: {key} must be a non-empty string, got {value!r}")
    return value.strip()


def _choice(data: dict, key: str, choices: tuple[str, ...], where: str) -> str:
    """The value of ``key``, one of ``choices`` (the first when absent)."""
    value = data.get(key, choices[0])
    if value not in choices:
        raise ConfigError(f"{where}: {key} must be one of {', '.join(choices)}, got {value!r}")
    return value


def _mapping(data: dict, key: str, where: str) -> dict:
    value = data.get(key) or {}
    if not isinstance(value, dict):
        raise ConfigError(f"{where}: {key} must be a mapping, got {value!r}")
    return value


def _xacro_args(values: dict, where: str) -> dict[str, str]:
    for key, value in values.items():
        if not isinstance(value, (str, int, float, bool)):
            raise ConfigError(f"{where}: xacro_args.{key} must be a scalar, got {value!r}")
    return {str(key): xacro_value(value) for key, value in values.items()}


def _named_states(values: dict, where: str) -> dict[str, list[float]]:
    states = {}
    for name, q in values.items():
        if not isinstance(q, list) or not all(_is_number(v) for v in q):
            raise ConfigError(f"{where}: named_states.{name} must be a list of numbers, got {q!r}")
        states[str(name)] = [float(v) for v in q]
    return states


def _positions(values: dict, where: str) -> dict[str, float]:
    for name, value in values.items():
        if not _is_number(value):
            raise ConfigError(f"{where}: default_positions.{name} must be a number, got {value!r}")
    return {str(name): float(value) for name, value in values.items()}


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _file(value: str, base: Path, key: str, where: str) -> str:
    """An absolute path for a path relative to ``base`` (which must exist); a URI unchanged."""
    if not value or is_uri(value):
        return value
    path = _absolute(base / value)
    if not path.is_file():
        raise ConfigError(f"{where}: {key}: no such file {path}")
    return str(path)


def _folder(value, base: Path, key: str, where: str) -> str:
    value = str(value) if isinstance(value, Path) else value
    if not isinstance(value, str) or not value.strip():
        raise ConfigError(f"{where}: {key} must be a folder path, got {value!r}")
    if is_uri(value.strip()):  # a folder inside another package
        return value.strip()
    path = _absolute(base / value.strip())
    if not path.is_dir():
        raise ConfigError(f"{where}: {key}: no such folder {path}")
    return str(path)


def _absolute(path: Path) -> Path:
    return Path(os.path.normpath(path.absolute()))
