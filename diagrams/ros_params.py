"""ROS navigation parameter files as navigation scenario overrides (``navigate --params FILE``).

Three forms are read, as ROS users have them:

* nav2's ``nav2_params.yaml``: node names, then ``ros__parameters``, then the node's keys
  (``amcl: {ros__parameters: {alpha1: 0.2, ...}}``, ``local_costmap: {local_costmap:
  {ros__parameters: ...}}``);
* a ROS 1 parameter YAML (rosparam): a node's keys at the top, or under their namespaces
  (``DWAPlannerROS: {max_vel_x: ...}``, costmap_common's keys);
* a ROS 1 launch XML: the ``<param name= value=>`` elements of its ``amcl`` node
  (``$(arg name)`` replaced by the ``<arg>``'s default or value).

What is mapped (to the scenario's keys, ``--set``'s names):

* AMCL -> ``amcl.*`` (``AmclConfig``): ROS 1's names are the scenario's; nav2's renamed ones
  are mapped back (``alpha1``-``alpha5``, ``max_beams``, ``z_hit``, ``z_rand``, ``sigma_hit``,
  ``pf_err``, ``pf_z``, ``robot_model_type``, ``initial_pose``);
* costmaps -> ``navigator.costmap.*``: ``robot_radius``, the inflation layer's
  ``inflation_radius`` and ``cost_scaling_factor``, the obstacle sources' ranges (ROS 1's
  ``obstacle_range``, ``raytrace_range``), ``track_unknown_space``, the local costmap's
  ``width`` and ``height`` (one costmap here: a key in both costmaps takes the later value);
* DWA (ROS 1) and DWB (nav2, only when ``FollowPath`` is DWB: MPPI's keys mean other things)
  -> ``navigator.controller.*``: speed and acceleration limits, ``sim_time``, samples, the
  scoring biases (DWB's ``PathDist``, ``GoalDist``, ``PathAlign`` and ``BaseObstacle``
  critics' ``scale``, ``PathAlign.forward_point_distance``), the goal checker's tolerances,
  ``controller_frequency``;
* the local planner: move_base's ``base_local_planner`` (``teb_local_planner/TebLocalPlannerROS``
  or DWA's) or nav2's ``FollowPath`` plugin -> ``navigator.local_planner`` (``teb``, ``dwa``);
  ``TebLocalPlannerROS``'s keys -> ``navigator.teb.*`` (``TebConfig``: ``dt_ref``,
  ``min_obstacle_dist``, the weights, ...), its limits and tolerances ->
  ``navigator.controller.*`` (``max_vel_x_backwards`` as ``min_vel_x``, negated);
* NavFn and GlobalPlanner -> ``navigator.planner.*``: ``tolerance``, ``use_astar`` (or
  ``use_dijkstra``, inverted), ``allow_unknown``, ``neutral_cost``, ``cost_factor``,
  ``lethal_cost``; nav2's Smac 2D (``SmacPlanner2D``: A*, its ``cost_travel_multiplier`` as
  ``cost_factor`` in the neutral cost's units); another planner plugin is listed as ignored.

* the progress checker (nav2's ``required_movement_radius`` and ``movement_time_allowance``,
  move_base's ``oscillation_distance`` and ``oscillation_timeout``) ->
  ``navigator.recovery.progress_distance`` and ``progress_timeout``: too little movement in
  that time starts the recovery behaviours.

* ``footprint`` polygons -> ``navigator.costmap.footprint``, with ``robot_radius`` its inscribed
  radius (nav2 ignores ``robot_radius`` when a footprint is set): the costmap inflates around
  that radius and the local planner checks the polygon at every pose it tries.

Every other key (frames, topics, rates, other plugins) is listed in one warning line as
ignored. Values are checked by the scenario's own checks, so a malformed one is
one ``ConfigError`` naming the file and the (scenario's) key.
"""

from __future__ import annotations

import json
import logging
import re
import xml.etree.ElementTree as ET
from dataclasses import fields
from pathlib import Path

import yaml

from drake_sim.base.config import parse_yaml, read_text
from drake_sim.base.errors import ConfigError
from drake_sim.navigation.costmap import INSCRIBED, footprint_radii
from drake_sim.navigation.global_planner import GlobalPlannerConfig
from drake_sim.navigation.teb_planner import TebConfig
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

_CONTROLLER = {
    **{k: k for k in ("max_vel_x", "min_vel_x", "max_vel_theta", "min_vel_theta", "acc_lim_x")},
    **{k: k for k in ("acc_lim_theta", "sim_time", "vx_samples", "vtheta_samples")},
    **{k: k for k in ("path_distance_bias", "goal_distance_bias", "occdist_scale")},
    **{k: k for k in ("forward_point_distance", "xy_goal_tolerance", "yaw_goal_tolerance")},
    "controller_frequency": "controller_frequency",
    "max_rot_vel": "max_vel_theta",  # ROS 1 DWA's older names
    "min_rot_vel": "min_vel_theta",
    "acc_lim_th": "acc_lim_theta",
    "vth_samples": "vtheta_samples",
    "PathDist.scale": "path_distance_bias",  # nav2 DWB's critics, as ROS 1 DWA's biases
    "GoalDist.scale": "goal_distance_bias",
    "PathAlign.scale": "path_align_bias",
    "PathAlign.forward_point_distance": "forward_point_distance",
    "BaseObstacle.scale": "occdist_scale",
}
"""DWA / DWB keys (the last name of their path) -> ``navigator.controller`` keys."""
_COSTMAP = {
    **{k: k for k in ("robot_radius", "inflation_radius", "cost_scaling_factor")},
    **{k: k for k in ("obstacle_max_range", "obstacle_min_range", "raytrace_max_range")},
    "track_unknown_space": "track_unknown_space",
    "obstacle_range": "obstacle_max_range",  # ROS 1
    "raytrace_range": "raytrace_max_range",
    "width": "local_width",  # the local (rolling) costmap's
    "height": "local_height",
}
"""Costmap keys -> ``navigator.costmap`` keys (one costmap here: the later file value wins)."""
_PLANNER = {
    **{k: k for k in ("tolerance", "use_astar", "allow_unknown", "neutral_cost", "cost_factor")},
    "lethal_cost": "lethal_cost",
}
"""NavFn / GlobalPlanner keys -> ``navigator.planner`` keys (``use_dijkstra`` is inverted)."""
_PROGRESS = {
    "required_movement_radius": "progress_distance",  # nav2's progress checker
    "movement_time_allowance": "progress_timeout",
    "oscillation_distance": "progress_distance",  # move_base's
    "oscillation_timeout": "progress_timeout",
}
"""Progress-checker keys -> ``navigator.recovery`` keys (a timeout of 0, "never", is ignored)."""
_TEB = {f.name for f in fields(TebConfig)}
"""teb_local_planner's keys -> ``navigator.teb`` keys (its limits are the controller's)."""
_LOCAL_PLANNERS = (
    "DWAPlannerROS",
    "TrajectoryPlannerROS",
    "TebLocalPlannerROS",
    "FollowPath",
    "move_base",
)
_GLOBAL_PLANNERS = ("GlobalPlanner", "NavfnROS", "GridBased")


def ros_overrides(path: Path | str) -> list[str]:
    """The scenario overrides (``amcl.*``, ``navigator.costmap.*``, ``navigator.controller.*``,
    ``navigator.planner.*``) a parameter file holds (see the module); logs one warning line
    naming every key it ignores.

    Raises:
        ConfigError: an unreadable or malformed file.
    """
    path = Path(path)
    where = str(path)
    text = read_text(path, "parameter file")
    if path.suffix in (".launch", ".xml") or text.lstrip().startswith("<"):
        amcl, ignored = _launch_params(text, where)
        navigator = {}
    else:
        amcl, navigator, ignored = _yaml_params(parse_yaml(text, where), where)
    overrides = [f"amcl.{key}={json.dumps(value)}" for key, value in amcl.items()]
    overrides += [f"navigator.{key}={json.dumps(value)}" for key, value in navigator.items()]
    if ignored:
        _log.warning("%s: ignored keys %s (no meaning here yet)", where, ", ".join(ignored))
    return overrides


def _nodes(tree: dict, prefix: tuple = ()) -> list[tuple[tuple, dict]]:
    """nav2's nodes: (the keys down to a ``ros__parameters``, its parameters), at any depth
    (``local_costmap: {local_costmap: {ros__parameters: ...}}``)."""
    found = []
    for name, block in tree.items():
        if not isinstance(block, dict):
            continue
        if isinstance(block.get("ros__parameters"), dict):
            found.append(((*prefix, str(name)), block["ros__parameters"]))
        else:
            found += _nodes(block, (*prefix, str(name)))
    return found


def _yaml_params(tree, where: str) -> tuple[dict, dict, list[str]]:
    if not isinstance(tree, dict):
        raise ConfigError(f"{where}: expected a mapping of parameters")
    nodes = _nodes(tree)
    if not nodes:  # ROS 1: a node's keys at the top level, or under their namespaces
        amcl, rest = _amcl(tree, nav2=False, where=where)
        navigator, ignored = _navigator({k: tree[k] for k in rest}, (), where)
        return amcl, navigator, ignored
    amcl, navigator, ignored = {}, {}, []
    for names, params in nodes:
        if names[-1] == "amcl":
            amcl, skipped = _amcl(params, nav2=True, where=where)
            ignored += [f"amcl.{key}" for key in skipped]
        else:
            mapped, skipped = _navigator(params, names, where)
            navigator.update(mapped)
            ignored += [f"{names[-1]}.{key}" for key in skipped]
    held = {names[0] for names, _ in nodes}
    ignored += [str(name) for name in tree if name not in held]
    return amcl, navigator, ignored


def _navigator(params: dict, node: tuple, where: str) -> tuple[dict, list[str]]:
    """(``navigator`` key -> value, ignored dotted keys) of a costmap, controller or planner
    node's parameters (nav2: ``node`` its names; ROS 1: empty, namespaces in the keys)."""
    mapped, ignored = {}, []
    for path, value in _flat(params):
        plugin = path[-1] == "plugin" and "FollowPath" in (*node, *path)
        if path[-1] == "base_local_planner" or plugin:  # move_base's choice, nav2's plugin
            name = str(value).lower()
            if "teb" in name:
                mapped["local_planner"] = "teb"
            elif "dwa" in name or "dwb" in name or "trajectoryplanner" in name:
                mapped["local_planner"] = "dwa"
            else:
                ignored.append(".".join(path))
            continue
        if path[-1] == "plugin" and "planner_server" in node:  # nav2's global planner
            name = str(value).lower()
            if "smacplanner2d" in name:  # A* on the grid, as here
                mapped["planner.use_astar"] = True
            elif "navfn" not in name:
                ignored.append(".".join(path))
            continue
        if path[-1] == "cost_travel_multiplier" and "planner_server" in node:  # Smac's
            neutral = GlobalPlannerConfig().neutral_cost  # Smac: 1 + m * cost / 252 per cell
            mapped["planner.cost_factor"] = float(value) * neutral / (INSCRIBED - 1)
            continue
        if path[-1] == "max_vel_x_backwards" and "TebLocalPlannerROS" in (*node, *path):
            mapped["controller.min_vel_x"] = -abs(float(value))
            continue
        if path[-1] == "footprint" and not set(path[:-1]) - {"local_costmap", "global_costmap"}:
            footprint = _footprint(value, where)
            if footprint:  # nav2's "[]" is none: robot_radius then
                inscribed = footprint_radii(footprint)[0]
                mapped["costmap.footprint"] = footprint
                mapped["costmap.robot_radius"] = inscribed
            continue
        target = _target((*node, *path), params)
        if target is None or (target[0] == "recovery" and value == 0):
            ignored.append(".".join(path))
        elif not (target[1] == "robot_radius" and "costmap.footprint" in mapped):
            section, key = target
            if key == "use_dijkstra":
                key, value = "use_astar", not value
            mapped[f"{section}.{key}"] = value
    return mapped, ignored


def _target(path: tuple, params: dict) -> tuple[str, str] | None:
    """Where a parameter at ``path`` (node names, namespaces and key) goes, or None."""
    key = path[-1]
    if len(path) > 1 and f"{path[-2]}.{key}" in _CONTROLLER:  # a critic's keys, nested
        key, path = f"{path[-2]}.{key}", (*path[:-2], f"{path[-2]}.{key}")
    scope = set(path[:-1])
    if key == "controller_frequency":  # move_base's and controller_server's
        return "controller", key
    if key in _PROGRESS and (not scope or scope & {"controller_server", "move_base"}):
        return "recovery", _PROGRESS[key]
    if "TebLocalPlannerROS" in scope and key in _TEB:
        return "teb", key
    if scope & {"controller_server", *_LOCAL_PLANNERS} and key in _CONTROLLER:
        follow = params.get("FollowPath", {})
        if "FollowPath" in scope and "dwb" not in str(follow.get("plugin", "dwb")).lower():
            return None  # another controller (MPPI, RPP): its keys mean other things
        return "controller", _CONTROLLER[key]
    if scope & {"planner_server", *_GLOBAL_PLANNERS} and (key in _PLANNER or key == "use_dijkstra"):
        return "planner", key
    costmap = scope & {"local_costmap", "global_costmap"} or not scope & {
        "controller_server",
        "planner_server",
        *_LOCAL_PLANNERS,
        *_GLOBAL_PLANNERS,
    }
    if costmap and key in _COSTMAP:
        if key in ("width", "height") and "local_costmap" not in scope:
            return None  # a global costmap's size is the map's here
        return "costmap", _COSTMAP[key]
    return None


def _footprint(value, where: str) -> list[list[float]]:
    """A footprint as nav2 (a string, ``"[[x, y], ...]"``) or ROS 1 (a list) writes it."""
    if isinstance(value, str):
        try:
            value = yaml.safe_load(value)
        except yaml.YAMLError:
            value = None
    ok = isinstance(value, list) and all(
        isinstance(p, list) and len(p) == 2 and all(isinstance(v, int | float) for v in p)
        for p in value
    )
    if not ok:
        raise ConfigError(f"{where}: 'footprint' must be a list of [x, y] points, got {value!r}")
    return [[float(v) for v in p] for p in value]


def _flat(params: dict, prefix: tuple = ()) -> list[tuple[tuple, object]]:
    items = []
    for key, value in params.items():
        if isinstance(value, dict):
            items += _flat(value, (*prefix, str(key)))
        else:
            items.append(((*prefix, str(key)), value))
    return items


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
