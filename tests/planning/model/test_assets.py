"""The Panda assets from example-robot-data: the installed description, the SRDF reader, and the
Drake-ready URDF generated into the cache (converted meshes, relative paths, a cache keyed by
every input, collision geometry options)."""

import importlib.metadata
import shutil
import xml.etree.ElementTree as ET

import pytest
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant

import planning.model.assets as mut
from drake_sim.base.resources import cache_dir

SRDF = """<?xml version="1.0"?>
<robot name="toy">
  <group name="arm"><chain base_link="a" tip_link="c"/></group>
  <group_state name="home" group="arm">
    <joint name="j1" value="0.5"/>
    <joint name="j2" value="-1.25"/>
  </group_state>
  <disable_collisions link1="a" link2="b" reason="Adjacent"/>
  <disable_collisions link1="b" link2="c" reason="Never"/>
</robot>
"""


def test_description_is_the_installed_package():
    path = mut.panda_description_dir()
    assert path.is_absolute() and path.name == "panda_description"
    for name in ("urdf/panda.urdf", "urdf/panda_collision.urdf", "srdf/panda.srdf"):
        assert (path / name).is_file()


def test_missing_package_is_a_clear_file_not_found(monkeypatch):
    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(mut.importlib.metadata, "distribution", missing)
    with pytest.raises(FileNotFoundError, match="example-robot-data"):
        mut.panda_description_dir()


def test_read_srdf_of_a_given_file(tmp_path):
    path = tmp_path / "toy.srdf"
    path.write_text(SRDF)
    info = mut.read_srdf(path)
    assert info.disabled_collisions == [("a", "b"), ("b", "c")]
    assert info.group_states == {"home": {"j1": 0.5, "j2": -1.25}}
    assert mut.read_srdf(tmp_path / "toy.srdf") == info


def test_read_srdf_of_the_panda():
    info = mut.read_srdf()
    assert ("panda_hand", "panda_leftfinger") in info.disabled_collisions
    assert all(len(pair) == 2 and pair[0] != pair[1] for pair in info.disabled_collisions)
    arm = {f"panda_joint{i}" for i in range(1, 8)}
    assert arm <= set(info.group_states["default"])


def meshes_of(urdf_text: str, element: str) -> list[str]:
    root = ET.fromstring(urdf_text)
    return [m.get("filename") for e in root.iter(element) for m in e.iter("mesh")]


@pytest.mark.parametrize("geometry", mut.COLLISION_GEOMETRIES)
def test_urdf_is_drake_ready(geometry):
    urdf = mut.panda_urdf(geometry)
    assert cache_dir() in urdf.parents and urdf.name == "panda.urdf"
    text = urdf.read_text()
    assert "package://" not in text and str(cache_dir()) not in text  # relative paths only
    assert "safety_controller" not in text
    visuals = meshes_of(text, "visual")
    assert visuals and all(f.startswith("../meshes/visual/") for f in visuals)
    assert all(f.endswith(".gltf") for f in visuals)
    collisions = meshes_of(text, "collision")
    if geometry == "convex_mesh":
        assert collisions and all(f.endswith(".obj") for f in collisions)
        assert text.count("declare_convex") == len(collisions)
    else:
        assert collisions == []  # spheres and cylinders only
    for filename in visuals + collisions:
        assert (urdf.parent / filename).is_file(), filename
    plant = MultibodyPlant(0.0)
    Parser(plant).AddModels(str(urdf))
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("panda_link0"))
    plant.Finalize()
    assert plant.num_positions() == 9  # 7 arm joints, 2 fingers


def test_unknown_collision_geometry_is_rejected():
    with pytest.raises(ValueError, match="collision_geometry 'voxels'"):
        mut.panda_urdf("voxels")


@pytest.fixture
def copied_description(tmp_path, monkeypatch):
    """A private copy of the description and cache, with mesh conversion counted (and faked:
    an empty file per mesh, so that no test here pays for trimesh)."""
    description = tmp_path / "panda_description"
    shutil.copytree(mut.panda_description_dir(), description)
    monkeypatch.setattr(mut, "panda_description_dir", lambda: description)
    monkeypatch.setenv("DRAKE_SIM_CACHE", str(tmp_path / "cache"))
    converted = []

    def convert(source, target):
        converted.append(source.name)
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text("")

    monkeypatch.setattr(mut, "_convert_mesh", convert)
    return description, converted


def test_urdf_is_generated_once_and_reused(copied_description):
    _, converted = copied_description
    first = mut.panda_urdf()
    assert converted and len(converted) == len(set(converted))  # each mesh once
    count = len(converted)
    assert mut.panda_urdf() == first
    assert len(converted) == count  # nothing converted again
    mut.panda_urdf("primitives")  # another folder: its meshes are converted there
    assert len(converted) > count


def test_changed_input_gets_a_new_cache_folder(copied_description):
    description, _ = copied_description
    before = mut.panda_urdf()
    urdf = description / "urdf" / "panda.urdf"
    urdf.write_text(urdf.read_text() + "<!-- edited -->\n")
    after = mut.panda_urdf()
    assert after != before and after.parent.parent.parent == before.parent.parent.parent
    assert after.is_file() and before.is_file()
