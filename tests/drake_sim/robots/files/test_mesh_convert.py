"""Mesh files made Drake-ready: every format read, collision meshes as bare OBJ, visual meshes
with their colours as glTF, COLLADA units applied, glTF's y-up honoured, bad files named."""

import re

import numpy as np
import pytest
import trimesh

import drake_sim.robots.files.mesh_convert as mut
from drake_sim.base.errors import ConfigError


def coloured_box(size=0.1):
    mesh = trimesh.creation.box(extents=(size, 2 * size, 3 * size))
    mesh.visual.face_colors = [200, 30, 30, 255]
    return mesh


@pytest.fixture
def meshes(tmp_path):
    """One box (0.1 x 0.2 x 0.3 m) in every format: STL (no colour), OBJ, COLLADA (red, and in
    millimetres), GLB (red)."""
    box = coloured_box()
    files = {"stl": tmp_path / "box.STL", "obj": tmp_path / "box.obj"}
    trimesh.Trimesh(box.vertices, box.faces).export(files["stl"])
    trimesh.Trimesh(box.vertices, box.faces).export(files["obj"])
    dae = trimesh.exchange.dae.export_collada(box)
    files["dae"] = tmp_path / "box.dae"
    files["dae"].write_bytes(dae)
    millimetres = coloured_box(size=100.0)  # the same box, in mm
    text = trimesh.exchange.dae.export_collada(millimetres).decode()
    text = text.replace("<asset>", '<asset><unit meter="0.001" name="millimeter"/>', 1)
    files["dae_mm"] = tmp_path / "box_mm.dae"
    files["dae_mm"].write_text(text)
    files["glb"] = tmp_path / "box.glb"
    files["glb"].write_bytes(trimesh.exchange.gltf.export_glb(trimesh.Scene(box)))
    return files


@pytest.mark.parametrize("kind", ["stl", "obj", "dae", "dae_mm"])
def test_every_format_reads_in_metres(meshes, kind):
    scene = mut.load_mesh_scene(meshes[kind])
    assert np.allclose(scene.extents, [0.1, 0.2, 0.3], atol=1e-6)


def test_gltf_is_read_z_up_as_drake_reads_it(meshes):
    # glTF's y axis is up: the 0.2 m side (y in the file) becomes z, the 0.3 m side (z) -y.
    assert np.allclose(mut.load_mesh_scene(meshes["glb"]).extents, [0.1, 0.3, 0.2], atol=1e-6)


def test_appearance_is_told_apart(meshes):
    assert not mut.has_appearance(mut.load_mesh_scene(meshes["stl"]))
    assert mut.has_appearance(mut.load_mesh_scene(meshes["dae"]))
    assert mut.has_appearance(mut.load_mesh_scene(meshes["glb"]))


def test_collision_obj_is_bare_geometry(meshes, tmp_path):
    out = mut.convert_mesh(meshes["dae"], tmp_path / "out" / "box.obj")
    text = out.read_text()
    assert "mtllib" not in text and "usemtl" not in text and "vn " not in text
    assert np.allclose(trimesh.load(out).extents, [0.1, 0.2, 0.3], atol=1e-6)


def test_visual_gltf_keeps_its_colour_and_size(meshes, tmp_path):
    out = mut.convert_mesh(meshes["dae"], tmp_path / "box.gltf")
    assert '"uri":"data:' in out.read_text().replace(" ", "")  # buffers embedded
    again = mut.load_mesh_scene(out)  # read back z-up, as Drake reads it
    assert np.allclose(again.extents, [0.1, 0.2, 0.3], atol=1e-6)
    (geometry,) = again.geometry.values()
    assert tuple(geometry.visual.material.main_color[:3]) == (200, 30, 30)


def test_no_partial_file_is_left(meshes, tmp_path):
    out = mut.convert_mesh(meshes["stl"], tmp_path / "box.obj")
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []
    assert out.is_file()


@pytest.mark.parametrize(
    ("name", "data", "match"),
    [
        ("mesh.stl", b"solid nothing\nendsolid nothing\n", "no triangles|cannot be read"),
        ("mesh.dae", b"<COLLADA>broken", "cannot be read"),
        ("mesh.xyz", b"1 2 3", "unsupported format"),
    ],
)
def test_bad_files_are_config_errors_naming_them(tmp_path, name, data, match):
    path = tmp_path / name
    path.write_bytes(data)
    with pytest.raises(ConfigError, match=match) as info:
        mut.load_mesh_scene(path)
    assert str(path) in str(info.value)


def test_only_obj_and_gltf_are_written(meshes, tmp_path):
    with pytest.raises(ValueError, match=r"\.glb"):
        mut.convert_mesh(meshes["stl"], tmp_path / "box.glb")


def test_unit_names_and_factors():
    assert mut._unit_scale(None) == 1.0
    assert mut._unit_scale("meters") == 1.0
    assert mut._unit_scale("0.001 * meters") == pytest.approx(0.001)
    assert mut._unit_scale("millimeters") == pytest.approx(0.001)
    assert mut._unit_scale("furlongs of nothing") == 1.0
    assert re.fullmatch(r"\d+\.\d+.*", mut.trimesh_version())
