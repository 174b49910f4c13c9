"""A robot's files found and made Drake-ready: packages from the map and built in, every URI
form, xacro with $(find), meshes converted once into the cache with relative paths, what Drake
refuses left out, bad input named."""

import os
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import trimesh
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

import drake_sim.robots.files.robot_files as mut
from drake_sim.base.errors import ConfigError
from drake_sim.robots.files import mesh_convert
from planning.model.description import load_robot_description
from planning.model.srdf import parse_srdf
from tests.robot_helpers import MOVEIT_SRDF, make_toy_robot


@pytest.fixture
def toy(tmp_path):
    """The toy robot's description (``tests/robot_helpers.py``), its YAML in ``tmp_path``."""
    return load_robot_description(make_toy_robot(tmp_path))


@pytest.fixture
def own_cache(tmp_path, monkeypatch):
    """An empty cache of the test's own."""
    monkeypatch.setenv("DRAKE_SIM_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def errors(call) -> str:
    with pytest.raises(ConfigError) as info:
        call()
    return str(info.value)


# ----------------------------------------------------------------------------- packages ----
def test_a_package_comes_from_the_map_first(tmp_path):
    (tmp_path / "mine").mkdir()
    found = mut.resolve_package(
        "example-robot-data", {"example-robot-data": str(tmp_path / "mine")}
    )
    assert found == (tmp_path / "mine").resolve()


def test_example_robot_data_is_built_in():
    folder = mut.resolve_package("example-robot-data")
    assert (folder / "robots" / "panda_description" / "urdf" / "panda.urdf").is_file()


def test_a_package_may_be_a_folder_in_another():
    folder = mut.resolve_package(
        "panda_description",
        {"panda_description": "package://example-robot-data/robots/panda_description"},
    )
    assert (folder / "srdf" / "panda.srdf").is_file()


def test_an_unknown_package_names_itself_and_the_known_ones(tmp_path):
    message = errors(lambda: mut.resolve_package("nope", {"mine": str(tmp_path)}))
    assert "'nope'" in message and "mine" in message
    assert "example-robot-data" in message and "vamp_resources" in message


def test_a_package_folder_that_is_not_there_is_named(tmp_path):
    message = errors(lambda: mut.resolve_package("gone", {"gone": str(tmp_path / "gone")}))
    assert "gone" in message and str(tmp_path / "gone") in message


def test_vamp_resources_are_fetched_when_first_named(tmp_path, monkeypatch):
    from drake_sim.robots.files import vamp_resources

    calls = []

    def fetched():
        calls.append(1)
        (tmp_path / "vamp").mkdir(exist_ok=True)
        return tmp_path / "vamp"

    monkeypatch.setattr(vamp_resources, "ensure_resources", fetched)
    assert mut.resolve_package("vamp_resources") == (tmp_path / "vamp").resolve()
    assert calls == [1]


def test_uri_forms(tmp_path):
    packages = {"pkg": str(tmp_path)}
    base = tmp_path / "urdf"
    assert (
        mut.resolve_uri("package://pkg/meshes/a.stl", base, packages)
        == tmp_path.resolve() / "meshes/a.stl"
    )
    assert (
        mut.resolve_uri("$(find pkg)/meshes/a.stl", base, packages)
        == tmp_path.resolve() / "meshes/a.stl"
    )
    assert mut.resolve_uri("file:///abs/a%20b.stl", base, packages) == Path("/abs/a b.stl")
    assert mut.resolve_uri("/abs/a.stl", base, packages) == Path("/abs/a.stl")
    assert mut.resolve_uri("../meshes/a.stl", base, packages) == base / "../meshes/a.stl"
    assert "http" in errors(lambda: mut.resolve_uri("http://host/a.stl", base, packages))


def test_relative_package_paths_are_relative_to_the_yaml(toy, tmp_path):
    assert mut.package_map(toy) == {"toy_description": str(tmp_path / "toy_description")}
    assert mut.description_base(toy) == tmp_path


# -------------------------------------------------------------------------------- xacro ----
def test_xacro_is_rendered_with_its_args_and_find(toy):
    root = ET.fromstring(mut.urdf_text(toy))
    (tool,) = [j for j in root.iter("joint") if j.get("name") == "tool_joint"]
    assert tool.find("origin").get("xyz") == "0 0 0.25"
    meshes = [m.get("filename") for m in root.iter("mesh")]
    assert str(Path(toy.package_paths["toy_description"]) / "meshes" / "base.stl") in meshes


def test_xacro_with_an_unknown_package_names_it(tmp_path):
    path = tmp_path / "r.urdf.xacro"
    path.write_text(
        '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">'
        '<xacro:include filename="$(find missing_pkg)/x.xacro"/><link name="a"/></robot>'
    )
    message = errors(lambda: mut.read_robot_file(path, {"other": str(tmp_path)}))
    assert "missing_pkg" in message and "other" in message


@pytest.mark.skipif(not MOVEIT_SRDF.is_dir(), reason=f"no real MoveIt files at {MOVEIT_SRDF}")
def test_moveit_srdf_xacro_with_find(tmp_path):
    config = tmp_path / "moveit_resources_panda_moveit_config" / "config"
    config.mkdir(parents=True)
    for name in ("panda_arm_hand.srdf.xacro", "panda_arm.xacro", "hand.xacro"):
        shutil.copy(MOVEIT_SRDF / name, config / name)
    packages = {"moveit_resources_panda_moveit_config": str(config.parent)}
    text = mut.read_robot_file(config / "panda_arm_hand.srdf.xacro", packages)
    srdf = parse_srdf(text, "panda_arm_hand.srdf.xacro")
    assert list(srdf.groups) == ["panda_arm", "hand", "panda_arm_hand"]
    assert set(srdf.group_states["panda_arm"]) == {"ready", "extended", "transport"}


# --------------------------------------------------------------------------- drake_urdf ----
def test_drake_urdf_converts_every_mesh_with_relative_paths(toy, own_cache):
    out = mut.drake_urdf(toy)
    assert out.parent.parent == own_cache / "robots" and out.name == "toy.urdf"
    root = ET.parse(out).getroot()
    by_link = {
        (link.get("name"), kind): shape.find("geometry/mesh")
        for link in root.iter("link")
        for kind in ("visual", "collision")
        for shape in link.findall(kind)
        if shape.find("geometry/mesh") is not None
    }
    for (_link, kind), mesh in by_link.items():
        name = mesh.get("filename")
        assert not os.path.isabs(name) and name.startswith("meshes/")
        assert (out.parent / name).is_file()
        assert name.endswith(".obj") or kind == "visual"
    assert by_link["base", "visual"].get("filename").endswith(".gltf")  # COLLADA, red
    assert by_link["link1", "visual"].get("filename").endswith(".gltf")  # GLB, green
    assert by_link["link2", "visual"].get("filename").endswith(".obj")  # STL: the URDF's grey
    assert by_link["link1", "visual"].get("scale") == "2 2 2"
    assert by_link["link2", "visual"].get("filename") == by_link["link2", "collision"].get(
        "filename"
    )


def test_drake_urdf_leaves_out_what_drake_refuses_or_ignores(toy, own_cache):
    root = ET.parse(mut.drake_urdf(toy)).getroot()
    assert root.find("transmission") is None and root.find("gazebo") is None
    assert root.find("joint/safety_controller") is None
    materials = {m.get("name") for m in root.iter("material")}
    assert "grey" in materials and "nowhere" not in materials


def test_drake_parses_the_converted_urdf(toy, own_cache):
    plant, _ = AddMultibodyPlantSceneGraph(DiagramBuilder(), 0.0)
    (instance,) = Parser(plant).AddModels(str(mut.drake_urdf(toy)))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("base", instance))
    plant.Finalize()
    assert plant.num_positions() == 3


def test_a_second_call_hits_the_cache(toy, own_cache, monkeypatch):
    first = mut.drake_urdf(toy)
    stamps = {p: p.stat().st_mtime_ns for p in first.parent.rglob("*") if p.is_file()}

    def no_conversion(*args, **kwargs):
        raise AssertionError("converted again")

    monkeypatch.setattr(mesh_convert, "convert_mesh", no_conversion)
    monkeypatch.setattr(mesh_convert, "load_mesh_scene", no_conversion)
    assert mut.drake_urdf(toy) == first
    assert {p: p.stat().st_mtime_ns for p in first.parent.rglob("*") if p.is_file()} == stamps


def test_changed_inputs_convert_again(toy, own_cache):
    first = mut.drake_urdf(toy)
    toy.xacro_args = {"tool_length": "0.5"}
    second = mut.drake_urdf(toy)
    mesh = Path(toy.package_paths["toy_description"]) / "meshes" / "link2.stl"
    mesh.write_bytes(mesh.read_bytes())  # touched, the same bytes
    assert mut.drake_urdf(toy) == second
    trimesh.creation.box(extents=(0.3, 0.3, 0.3)).export(mesh)
    third = mut.drake_urdf(toy)
    assert len({first.parent, second.parent, third.parent}) == 3


def test_mesh_files_lists_each_file_once(toy):
    names = [p.name for p in mut.mesh_files(toy)]
    assert names == ["base.dae", "base.stl", "link1.glb", "link1.obj", "link2.stl"]


def test_a_missing_mesh_names_the_link_and_the_file(toy, own_cache):
    missing = Path(toy.package_paths["toy_description"]) / "meshes" / "link1.obj"
    missing.unlink()
    message = errors(lambda: mut.drake_urdf(toy))
    assert "'link1'" in message and "collision" in message and str(missing.resolve()) in message


def test_a_mesh_in_an_unknown_package_names_it(toy, own_cache):
    xacro = Path(toy.package_paths["toy_description"]) / "urdf" / "toy.urdf.xacro"
    xacro.write_text(
        xacro.read_text().replace(
            "package://toy_description/meshes/link2", "package://elsewhere/link2"
        )
    )
    message = errors(lambda: mut.drake_urdf(toy))
    assert "'elsewhere'" in message and "toy_description" in message and "'link2'" in message


def test_not_a_urdf_is_a_config_error(toy, own_cache):
    message = errors(lambda: mut.drake_urdf(toy, "<robot"))
    assert "not a URDF" in message


def test_a_missing_visual_mesh_is_left_out_with_one_warning(toy, own_cache, caplog):
    """A checkout without its visual meshes (TurtleBot3's ``bases/`` missing) still loads: the
    link keeps its collision geometry and is shown without the mesh."""
    missing = Path(toy.package_paths["toy_description"]) / "meshes" / "link1.glb"
    missing.unlink()
    with caplog.at_level("WARNING"):
        urdf = mut.drake_urdf(toy)
    (record,) = [r for r in caplog.records if "visual meshes not found" in r.getMessage()]
    assert "'link1'" in record.getMessage() and "link1.glb" in record.getMessage()
    root = ET.parse(urdf).getroot()
    link1 = next(link for link in root.iter("link") if link.get("name") == "link1")
    assert link1.find("visual") is None and link1.find("collision") is not None
    caplog.clear()
    with caplog.at_level("WARNING"):
        assert mut.drake_urdf(toy, warn=False) == urdf  # the caller warned already
    assert not caplog.records


def test_a_urdf_with_xacro_in_it_is_rendered(tmp_path):
    """ROS 2's TurtleBot3 ``.urdf`` files hold ``xacro:arg`` and ``${}``: rendered, as the
    launch files do."""
    urdf = tmp_path / "robot.urdf"
    urdf.write_text(
        '<robot name="r" xmlns:xacro="http://ros.org/wiki/xacro">'
        '<xacro:arg name="namespace" default="ns_"/>'
        '<xacro:property name="namespace" value="$(arg namespace)"/>'
        '<link name="${namespace}base"/></robot>'
    )
    assert 'name="ns_base"' in mut.read_robot_file(urdf)
    plain = tmp_path / "plain.urdf"
    plain.write_text('<robot name="r"><link name="${kept}"/></robot>')
    assert "${kept}" in mut.read_robot_file(plain)  # no xacro namespace: read as it is
