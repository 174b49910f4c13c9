"""drake_sim.base.resources: the project's folders, package:// URIs, the Drake parser that
resolves them, and the content-keyed cache of rendered xacro files."""

import pytest
import yaml
from pydrake.multibody.plant import MultibodyPlant

import drake_sim.base.resources as mut

XACRO = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="$(arg name)">
  <xacro:property name="cfg" value="${xacro.load_yaml('$(arg config)')}"/>
  <link name="${cfg['link']}"/>
</robot>
"""


@pytest.fixture
def cache(tmp_path, monkeypatch):
    path = tmp_path / "cache"
    monkeypatch.setenv("DRAKE_SIM_CACHE", str(path))
    return path


@pytest.fixture
def xacro_inputs(tmp_path):
    """A xacro file reading a YAML named by a mapping; returns (xacro file, mappings)."""
    folder = tmp_path / "model"
    folder.mkdir()
    xacro_file = folder / "thing.urdf.xacro"
    xacro_file.write_text(XACRO)
    config = tmp_path / "thing.yaml"
    config.write_text("link: body\n")
    return xacro_file, {"name": "thing", "config": str(config)}


def test_project_folders_exist():
    assert (mut.models_dir() / "package.xml").is_file()
    assert (mut.models_dir() / "worlds" / "ddrive.world.sdf").is_file()
    assert (mut.config_dir() / "flip.yaml").is_file()
    assert mut.models_dir().is_absolute() and mut.config_dir().is_absolute()


def test_cache_dir_follows_the_environment_and_is_created(cache):
    assert not cache.exists()
    assert mut.cache_dir() == cache
    assert cache.is_dir()


def test_package_uri_round_trip():
    uri = mut.package_uri("worlds/ddrive.world.sdf")
    assert uri == "package://drake_sim_models/worlds/ddrive.world.sdf"
    assert mut.package_uri("/worlds/ddrive.world.sdf") == uri  # a leading slash is dropped
    assert mut.resolve_uri(uri) == mut.models_dir() / "worlds" / "ddrive.world.sdf"
    assert mut.resolve_uri(uri).is_file()


def test_plain_paths_pass_through_and_unknown_packages_raise(tmp_path):
    assert mut.resolve_uri(str(tmp_path / "a.sdf")) == tmp_path / "a.sdf"
    with pytest.raises(ValueError, match="unknown package in URI 'package://other/a.sdf'"):
        mut.resolve_uri("package://other/a.sdf")


def test_make_parser_resolves_the_models_package():
    plant = MultibodyPlant(time_step=0.0)
    dut = mut.make_parser(plant, model_name_prefix="left")
    assert dut.package_map().GetPath(mut.PACKAGE_NAME) == str(mut.models_dir())
    (instance,) = dut.AddModels(url=mut.package_uri("cardboard_box/model.sdf"))
    assert plant.GetModelInstanceName(instance) == "left::cardboard_box"
    plant.Finalize()
    assert plant.HasBodyNamed("body", instance)


def test_render_xacro_caches_by_content(cache, xacro_inputs):
    xacro_file, mappings = xacro_inputs
    dut = mut.render_xacro(xacro_file, mappings)
    assert dut.parent == cache / "xacro" and dut.name.startswith("thing-")
    assert dut.suffix == ".urdf"
    text = dut.read_text()
    assert 'name="thing"' in text and '<link name="body"/>' in text
    # Same inputs: the cached file is returned as it is, without rendering again.
    dut.write_text(text + "<!-- cached -->\n")
    again = mut.render_xacro(str(xacro_file), mappings)
    assert again == dut and again.read_text().endswith("<!-- cached -->\n")


def test_render_xacro_renders_again_when_an_input_changes(cache, xacro_inputs):
    xacro_file, mappings = xacro_inputs
    first = mut.render_xacro(xacro_file, mappings)
    # The file a mapping names changed (same path, new content): a new file.
    config = mappings["config"]
    with open(config, "w") as f:
        f.write("link: chassis\n")
    second = mut.render_xacro(xacro_file, mappings)
    assert second != first and '<link name="chassis"/>' in second.read_text()
    assert first.is_file()  # the old result stays for the old inputs
    # A changed mapping value, and an edited xacro beside the rendered one: new files too.
    third = mut.render_xacro(xacro_file, {**mappings, "name": "other"})
    assert third not in (first, second) and 'name="other"' in third.read_text()
    (xacro_file.parent / "macros.xacro").write_text("<robot/>\n")
    fourth = mut.render_xacro(xacro_file, mappings)
    assert fourth not in (first, second, third)
    assert sorted(p.name for p in (cache / "xacro").iterdir()) == sorted(
        p.name for p in (first, second, third, fourth)
    )  # no temporary files left behind


def test_params_yaml_file_is_written_once_per_content():
    first = mut.params_yaml_file("robot", {"wheel": {"radius": 0.1}, "mass": 2.0})
    again = mut.params_yaml_file("robot", {"mass": 2.0, "wheel": {"radius": 0.1}})
    other = mut.params_yaml_file("robot", {"wheel": {"radius": 0.2}, "mass": 2.0})
    assert first == again != other
    assert first.name.startswith("robot-") and first.suffix == ".yaml"
    assert yaml.safe_load(first.read_text()) == {"wheel": {"radius": 0.1}, "mass": 2.0}
