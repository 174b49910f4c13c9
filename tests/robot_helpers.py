"""Robot descriptions for the robot model tests: a small robot written here in every file form a
description may take, and VAMP's four robots from wherever they can be had.

VAMP's descriptions are third-party files, not in the repository: the tests take the unpacked
copy of the ``vamp-planner`` sdist that pip leaves in the temporary folder (``dev_resources``)
when there is one, else ``drake_sim.robots.files.vamp_resources`` downloads the sdist with pip
into the session's cache; a test that cannot have them skips and says why. Call these from
fixtures or tests, never at import time (the session's cache folder is set by a fixture).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
import trimesh

from drake_sim.base.errors import ConfigError
from drake_sim.robots.files.vamp_resources import vamp_resources


def dev_resources() -> Path | None:
    """An unpacked copy of the vamp-planner sdist's ``resources/`` that ``pip download`` left
    in the temporary folder (``pip-download-*/vamp-planner_*``), or None. The oldest copy that
    holds the four robots' URDFs: a pip download running beside the tests (one fetching the
    descriptions into a test session's cache) unpacks into the same place, half-done for a
    while."""
    found = Path(tempfile.gettempdir()).glob("pip-download-*/vamp-planner_*/resources")
    found = sorted(found, key=lambda folder: folder.stat().st_mtime)
    robots = ("panda", "ur5", "fetch", "baxter")
    whole = (f for f in found if all((f / r / f"{r}.urdf").is_file() for r in robots))
    return next(whole, None)


MOVEIT_SRDF = Path(__file__).resolve().parents[2] / "shared" / "real_ros" / "moveit" / "srdf"
"""MoveIt's Panda SRDF xacros (``shared/real_ros/moveit/srdf``, beside the checkout)."""

_FOUND: dict = {}


def vamp_robot(robot: str) -> Path:
    """Returns VAMP's ``resources/<robot>`` in the cache (``package://vamp_resources/<robot>``),
    from ``dev_resources()`` or a download; skips the test, saying why, when neither works (a
    failure is remembered: one try per session)."""
    if isinstance(_FOUND.get("error"), ConfigError):
        pytest.skip(f"VAMP robot descriptions not available: {_FOUND['error']}")
    try:
        return vamp_resources(robot, dev_resources())
    except ConfigError as e:
        _FOUND["error"] = e
        pytest.skip(f"VAMP robot descriptions not available: {e}")


TOY_XACRO = """<?xml version="1.0"?>
<robot name="toy" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:arg name="tool_length" default="0.1"/>
  <material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>
  <xacro:macro name="inertial">
    <inertial><mass value="1"/>
      <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  </xacro:macro>
  <link name="base">
    <xacro:inertial/>
    <visual><geometry>
      <mesh filename="package://toy_description/meshes/base.dae"/></geometry></visual>
    <collision><geometry>
      <mesh filename="$(find toy_description)/meshes/base.stl"/></geometry></collision>
  </link>
  <link name="link1">
    <xacro:inertial/>
    <visual><geometry>
      <mesh filename="package://toy_description/meshes/link1.glb" scale="2 2 2"/>
    </geometry></visual>
    <collision><geometry>
      <mesh filename="../meshes/link1.obj" scale="2 2 2"/></geometry></collision>
  </link>
  <link name="link2">
    <xacro:inertial/>
    <visual><geometry><mesh filename="package://toy_description/meshes/link2.stl"/></geometry>
      <material name="grey"/></visual>
    <collision><geometry><mesh filename="package://toy_description/meshes/link2.stl"/></geometry></collision>
  </link>
  <link name="link3">
    <xacro:inertial/>
    <visual><geometry><box size="0.05 0.05 0.05"/></geometry><material name="nowhere"/></visual>
  </link>
  <link name="tool"/>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="link1"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" velocity="1.5" effort="10"/>
    <safety_controller soft_lower_limit="-1.5" soft_upper_limit="1.8" k_position="10"
      k_velocity="1"/>
  </joint>
  <joint name="j2" type="prismatic">
    <parent link="link1"/><child link="link2"/><origin xyz="0 0 0.1"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.2" velocity="0.5" effort="10"/>
  </joint>
  <joint name="j3" type="continuous">
    <parent link="link2"/><child link="link3"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit velocity="3" effort="10"/>
  </joint>
  <joint name="tool_joint" type="fixed">
    <parent link="link3"/><child link="tool"/><origin xyz="0 0 $(arg tool_length)"/>
  </joint>
  <transmission name="t1"><type>transmission_interface/SimpleTransmission</type>
    <joint name="j1"/></transmission>
  <gazebo reference="link1"><material>Gazebo/Grey</material></gazebo>
</robot>
"""

TOY_SRDF = """<?xml version="1.0"?>
<robot name="toy">
  <group name="arm"><chain base_link="base" tip_link="tool"/></group>
  <group name="first"><joint name="j1"/></group>
  <group_state name="home" group="arm">
    <joint name="j1" value="0.5"/><joint name="j2" value="0.1"/><joint name="j3" value="3.0"/>
  </group_state>
  <group_state name="partial" group="arm"><joint name="j1" value="0.1"/></group_state>
  <virtual_joint name="fixed_base" type="fixed" parent_frame="world" child_link="base"/>
  <disable_collisions link1="base" link2="link1" reason="Adjacent"/>
</robot>
"""

TOY_LIMITS = """joint_limits:
  j1: {has_velocity_limits: true, max_velocity: 0.75,
       has_acceleration_limits: true, max_acceleration: 2.0}
  j2: {has_position_limits: true, min_position: 0.05, max_position: 0.15}
  ghost: {has_velocity_limits: true, max_velocity: 1.0}
"""

XARM7_YAML = """urdf: package://example-robot-data/robots/xarm_description/urdf/xarm7.urdf
srdf: package://example-robot-data/robots/xarm_description/srdf/xarm7.srdf
"""
"""example-robot-data's xArm 7 as a two-line description YAML: an arm this project does not
ship, described only by the files of an installed package."""

TOY_YAML = """urdf: toy_description/urdf/toy.urdf.xacro
srdf: toy_description/srdf/toy.srdf
package_paths: {toy_description: toy_description}
group: arm
joint_limits: toy_description/config/joint_limits.yaml
xacro_args: {tool_length: 0.25}
"""


def _box(size=0.1, colour=None) -> trimesh.Trimesh:
    mesh = trimesh.creation.box(extents=(size, size, size))
    if colour is not None:
        mesh.visual.face_colors = colour
    return mesh


def make_toy_robot(folder: Path) -> Path:
    """Writes the toy robot into ``folder``: ``toy_description/`` (a xacro URDF naming COLLADA,
    STL, GLB and OBJ meshes by ``package://``, ``$(find)`` and relative paths, an SRDF and a
    ``joint_limits.yaml``) and ``toy.yaml`` describing it; returns the YAML's path."""
    package = folder / "toy_description"
    for sub in ("urdf", "srdf", "meshes", "config"):
        (package / sub).mkdir(parents=True, exist_ok=True)
    (package / "urdf" / "toy.urdf.xacro").write_text(TOY_XACRO)
    (package / "srdf" / "toy.srdf").write_text(TOY_SRDF)
    (package / "config" / "joint_limits.yaml").write_text(TOY_LIMITS)
    meshes = package / "meshes"
    (meshes / "base.dae").write_bytes(
        trimesh.exchange.dae.export_collada(_box(0.2, [200, 30, 30, 255]))
    )
    _box(0.2).export(meshes / "base.stl")
    scene = trimesh.Scene(_box(0.05, [30, 200, 30, 255]))
    (meshes / "link1.glb").write_bytes(trimesh.exchange.gltf.export_glb(scene))
    _box(0.05).export(meshes / "link1.obj")
    _box(0.08).export(meshes / "link2.stl")
    description = folder / "toy.yaml"
    description.write_text(TOY_YAML)
    return description


ELBOW_URDF = """<?xml version="1.0"?>
<robot name="elbow">
  <link name="base"><collision><origin xyz="0 0 0.05"/><geometry><box size="0.4 0.4 0.1"/>
    </geometry></collision></link>
  <link name="post"><collision><origin xyz="0 0 0.2"/><geometry><box size="0.06 0.06 0.2"/>
    </geometry></collision></link>
  <link name="arm"><collision><origin xyz="0.25 0 0"/><geometry><box size="0.3 0.05 0.05"/>
    </geometry></collision></link>
  <link name="tool"/>
  <joint name="pan" type="continuous"><parent link="base"/><child link="post"/>
    <origin xyz="0.1 0 0"/><axis xyz="0 0 1"/><limit velocity="1" effort="1"/></joint>
  <joint name="lift" type="revolute"><parent link="post"/><child link="arm"/>
    <origin xyz="0 0 0.35"/><axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="{lift_upper}" velocity="1" effort="1"/></joint>
  <joint name="tip" type="fixed"><parent link="arm"/><child link="tool"/>
    <origin xyz="0.4 0 0"/></joint>{finger}
</robot>
"""

ELBOW_FINGER = """
  <link name="finger"><collision><geometry><box size="0.02 0.02 0.02"/></geometry></collision>
  </link>
  <joint name="slide" type="prismatic"><parent link="arm"/><child link="finger"/>
    <origin xyz="0.42 0 0"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="0.05" velocity="1" effort="1"/></joint>"""

ELBOW_SRDF = """<?xml version="1.0"?>
<robot name="elbow">
  <group name="arm"><chain base_link="base" tip_link="tool"/></group>
  <disable_collisions link1="base" link2="post" reason="Adjacent"/>
  <disable_collisions link1="post" link2="arm" reason="Adjacent"/>
</robot>
"""


def make_elbow_robot(folder: Path, lift_upper: float, *, finger: bool = False) -> Path:
    """Writes a two-joint arm of boxes (a post turning on a plate, an arm lifting on the post)
    and its description YAML into ``folder``; returns the YAML's path. Its only checked pair,
    plate and arm, depends on both joints (the post turns off the plate's centre): with
    ``lift_upper`` 1.5 rad the arm's far end reaches the plate when turned over it, with 0.3
    rad it stays about 10 cm above. With ``finger``, a small block slides on the arm's end
    (joint ``slide``, outside the group)."""
    folder.mkdir(parents=True, exist_ok=True)
    urdf = ELBOW_URDF.format(lift_upper=lift_upper, finger=ELBOW_FINGER if finger else "")
    (folder / "elbow.urdf").write_text(urdf)
    (folder / "elbow.srdf").write_text(ELBOW_SRDF)
    description = folder / "elbow.yaml"
    description.write_text("urdf: elbow.urdf\nsrdf: elbow.srdf\ngroup: arm\n")
    return description


def elbow_scene(folder: Path, lift_upper: float, *, finger: bool = False):
    """A ``PlanningScene`` of ``make_elbow_robot``'s arm (no table)."""
    from planning import PlanningConfig, PlanningScene
    from planning.model.model_config import RobotModelConfig

    description = make_elbow_robot(folder, lift_upper, finger=finger)
    return PlanningScene(PlanningConfig(model=RobotModelConfig(description=str(description)),
                                        table=None))  # fmt: skip
