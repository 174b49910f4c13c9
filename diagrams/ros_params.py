"""ROS navigation parameter files as navigation scenario overrides (``navigate --params FILE``).

Three forms are read, as ROS users have them:

* nav2's ``nav2_params.yaml``: a node name, then ``ros__parameters``, then the node's keys
  (``amcl: {ros__parameters: {alpha1: 0.2, ...}}``);
* a ROS 1 parameter YAML (rosparam): the node's keys at the top (``amcl.yaml``);
* a ROS 1 launch XML: the ``<param name= value=>`` elements of its ``amcl`` node
  (``$(arg name)`` replaced by the ``<arg>``'s default or value).

The AMCL keys become ``amcl.*`` keys of the scenario (``AmclConfig``): ROS 1's names are the
scenario's; nav2's renamed ones are mapped back (``alpha1``-``alpha5`` to ``odom_alpha*``,
``max_beams``, ``z_hit``, ``z_rand``, ``sigma_hit``, ``pf_err``, ``pf_z``, ``robot_model_type``,
``initial_pose``). Every other key, of AMCL or of another node (costmaps, DWB, NavFn: not yet
mapped), is listed in one warning line as ignored; a value is checked by the scenario's own
checks, so a malformed one is one ``ConfigError`` naming the file and the key.
"""

from __future__ import annotations

import json
import logging
import re
import xml.etree.ElementTree as ET
from dataclasses import fields
from pathlib import Path

from drake_sim.base.config import parse_yaml, read_text
from drake_sim.base.errors import ConfigError
from drake_sim.systems.estimation.amcl_config import AmclConfig

_log = logging.getLogger(__name__)

_AMCL_KEYS = {f.name for f in fields(AmclConfig)}
_NAV2_AMCL = {
    **{f"alpha{i}": f"odom_alpha{i}" for i in range(1, 6)},
    "max_beams": "laser_max_beams",
    "z_hit": "laser_z_hit",
    "z_rand": "laser_z_rand",
    "sigma_hit": "laser_sigma_hit",
    "pf_err": "kld_err",
    "pf_z": "kld_z",
}
"""nav2's AMCL names that differ from ROS 1's (and the scenario's)."""
_MOTION_MODELS = {
    "nav2_amcl::DifferentialMotionModel": "diff-corrected",
    "nav2_amcl::OmniMotionModel": "omni-corrected",
}
"""nav2's ``robot_model_type`` plugins, as ROS 1's ``odom_model_type``."""


def amcl_overrides(path: Path | str) -> list[str]:
    """The ``amcl.KEY=VALUE`` overrides a parameter file holds (see the module); logs one
    warning line naming every key it ignores.

    Raises:
        ConfigError: an unreadable or malformed file, or one with no AMCL keys at all.
    """
    path = Path(path)
    where = str(path)
    text = read_text(path, "parameter file")
    if path.suffix in (".launch", ".xml") or text.lstrip().startswith("<"):
        amcl, ignored = _launch_params(text, where)
    else:
        amcl, ignored = _yaml_params(parse_yaml(text, where), where)
    overrides = [f"amcl.{key}={json.dumps(value)}" for key, value in amcl.items()]
    if ignored:
        _log.warning("%s: ignored keys %s (no meaning here yet)", where, ", ".join(ignored))
    if not overrides:
        raise ConfigError(f"{where}: no amcl parameters found")
    return overrides


def _yaml_params(tree, where: str) -> tuple[dict, list[str]]:
    if not isinstance(tree, dict):
        raise ConfigError(f"{where}: expected a mapping of parameters")
    nodes = {
        name: block["ros__parameters"]
        for name, block in tree.items()
        if isinstance(block, dict) and isinstance(block.get("ros__parameters"), dict)
    }
    if not nodes:  # ROS 1: one node's keys at the top level
        return _amcl(tree, nav2=False, where=where)
    amcl, ignored = {}, []
    for name, params in nodes.items():
        if name == "amcl":
            amcl, skipped = _amcl(params, nav2=True, where=where)
            ignored += [f"amcl.{key}" for key in skipped]
        else:
            ignored += [f"{name}.{key}" for key in _flat(params)]
    ignored += [str(name) for name in tree if name not in nodes]
    return amcl, ignored


def _flat(params: dict, prefix: str = "") -> list[str]:
    keys = []
    for key, value in params.items():
        if isinstance(value, dict):
            keys += _flat(value, f"{prefix}{key}.")
        else:
            keys.append(f"{prefix}{key}")
    return keys


def _amcl(params: dict, *, nav2: bool, where: str) -> tuple[dict, list[str]]:
    """(scenario AMCL key -> value, ignored keys) of one AMCL node's parameters."""
    amcl, ignored = {}, []
    for key, value in params.items():
        key = str(key)
        if key == "robot_model_type" and nav2:
            model = _MOTION_MODELS.get(str(value))
            if model is None:
                known = ", ".join(_MOTION_MODELS)
                raise ConfigError(f"{where}: 'amcl.robot_model_type' must be one of {known}")
            amcl["odom_model_type"] = model
        elif key == "initial_pose" and nav2 and isinstance(value, dict):
            names = {"x": "initial_pose_x", "y": "initial_pose_y", "yaw": "initial_pose_a"}
            amcl.update({names[k]: v for k, v in value.items() if k in names})
            ignored += [f"initial_pose.{k}" for k in value if k not in names]
        elif nav2 and key in _NAV2_AMCL:
            amcl[_NAV2_AMCL[key]] = value
        elif key in _AMCL_KEYS:
            amcl[key] = value
        else:
            ignored.append(key)
    return amcl, ignored


def _launch_params(text: str, where: str) -> tuple[dict, list[str]]:
    """The ``amcl`` node's ``<param>`` elements of a ROS 1 launch file, ``$(arg)`` resolved."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as e:
        raise ConfigError(f"{where}: malformed launch XML ({e})") from None
    args = {
        a.get("name"): a.get("value", a.get("default"))
        for a in root.iter("arg")
        if a.get("name") is not None
    }

    def resolve(value: str) -> str:
        def one(match):
            name = match.group(1)
            if args.get(name) is None:
                raise ConfigError(f"{where}: $(arg {name}) has no value or default")
            return str(args[name])

        return re.sub(r"\$\(arg\s+([^)\s]+)\)", one, value)

    params = {}
    for node in root.iter("node"):
        if node.get("pkg") != "amcl" and node.get("type") != "amcl":
            continue
        for param in node.iter("param"):
            name, value = param.get("name"), param.get("value")
            if name is None or value is None:
                continue
            params[name] = _number(resolve(value))
    if not params:
        return {}, []
    return _amcl(params, nav2=False, where=where)


def _number(text: str):
    """A launch file's value as YAML would read it (numbers and booleans; else the text)."""
    lowered = text.strip().lower()
    if lowered in ("true", "false"):
        return lowered == "true"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text
