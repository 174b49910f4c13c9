"""Far-from-convex collision meshes cut into convex pieces (``collision_meshes: pieces``): only
meshes worth it, the pieces' hulls holding the whole mesh, the converted URDF with one collision
per piece that Drake parses, cached, and bad settings or a missing CoACD named."""

import importlib.metadata
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import trimesh
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

import drake_sim.robots.files.mesh_pieces as mut
from drake_sim.base.errors import ConfigError
from drake_sim.robots.files import robot_files
from planning.model.description import load_robot_description
from tests.robot_helpers import make_toy_robot


def _two_boxes(gap=0.3) -> trimesh.Trimesh:
    """Two 0.1 m cubes ``gap`` apart (centres): closed; at 0.3 m filling half their hull,
    which strays 11 mm from them on average (the volume between over the hull's area)."""
    a = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    b = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    b.apply_translation([gap, 0.0, 0.0])
    return trimesh.util.concatenate([a, b])


def _inside(points: np.ndarray, hull: trimesh.Trimesh, tolerance=1e-6) -> np.ndarray:
    """Which points lie in the convex ``hull`` (every face plane's inner side)."""
    normals, origins = hull.face_normals, hull.triangles[:, 0]
    return np.all(np.einsum("fk,pfk->pf", normals, points[:, None] - origins) <= tolerance, axis=1)


def test_only_closed_meshes_far_from_convex_are_worth_cutting():
    box = trimesh.creation.box(extents=(0.1, 0.2, 0.3))
    assert not mut.worth_cutting(box)
    assert mut.worth_cutting(_two_boxes())
    assert not mut.worth_cutting(_two_boxes(0.12))  # 2 cm apart: the hull strays 1.9 mm
    open_mesh = _two_boxes()
    open_mesh.update_faces(np.arange(len(open_mesh.faces)) != 0)  # one triangle gone
    assert not open_mesh.is_watertight and not mut.worth_cutting(open_mesh)


def test_the_pieces_hulls_hold_the_whole_mesh_and_less_besides(tmp_path):
    mesh = _two_boxes()
    files = mut.convex_pieces(trimesh.Scene(mesh), tmp_path, "two")
    assert len(files) >= 2 and all(f.parent == tmp_path and f.suffix == ".obj" for f in files)
    hulls = [trimesh.load(f, force="mesh") for f in files]
    assert all(h.is_convex for h in hulls)
    # Every point of the mesh (its vertices and points on its faces) is in some piece's hull.
    points = np.vstack([mesh.vertices, trimesh.sample.sample_surface(mesh, 500, seed=1)[0]])
    held = np.zeros(len(points), dtype=bool)
    for hull in hulls:
        held |= _inside(points, hull)
    assert held.all()
    assert sum(h.volume for h in hulls) < 1.05 * mesh.volume < 0.6 * mesh.convex_hull.volume
    # The same input cuts the same pieces (seeded).
    again = mut.convex_pieces(trimesh.Scene(mesh), tmp_path / "again", "two")
    assert [f.read_bytes() for f in again] == [f.read_bytes() for f in files]


def test_a_mesh_not_worth_cutting_gives_no_pieces(tmp_path):
    box = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    assert mut.convex_pieces(trimesh.Scene(box), tmp_path, "box") == []
    assert not list(tmp_path.iterdir())


def test_without_coacd_the_setting_is_named(monkeypatch):
    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(importlib.metadata, "version", missing)
    with pytest.raises(ConfigError, match="collision_meshes: pieces needs the coacd package"):
        mut.coacd_version()


@pytest.fixture
def own_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("DRAKE_SIM_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def _toy_with_pieces(tmp_path, value="pieces"):
    """The toy robot with link2's collision mesh two boxes apart, described with
    ``collision_meshes: value``."""
    yaml = make_toy_robot(tmp_path)
    _two_boxes().export(tmp_path / "toy_description" / "meshes" / "link2.stl")
    yaml.write_text(yaml.read_text() + f"collision_meshes: {value}\n")
    return load_robot_description(yaml)


def _collision_files(urdf) -> dict[str, list[str]]:
    root = ET.parse(urdf).getroot()
    return {
        link.get("name"): [m.get("filename") for m in link.iterfind("collision/geometry/mesh")]
        for link in root.iter("link")
    }


def test_the_converted_urdf_has_one_collision_per_piece(tmp_path, own_cache):
    pieces = _toy_with_pieces(tmp_path)
    assert pieces.collision_meshes == "pieces"
    urdf = robot_files.drake_urdf(pieces)
    files = _collision_files(urdf)
    assert len(files["link2"]) >= 2 and all("-piece" in f for f in files["link2"])
    assert len(files["base"]) == 1 and "-piece" not in files["base"][0]  # a cube: left whole
    for name in files["link2"]:
        assert (urdf.parent / name).is_file()
    plant, scene_graph = AddMultibodyPlantSceneGraph(DiagramBuilder(), 0.0)
    (instance,) = Parser(plant).AddModels(str(urdf))
    plant.Finalize()
    link2 = plant.GetBodyByName("link2", instance)
    assert len(plant.GetCollisionGeometriesForBody(link2)) == len(files["link2"])
    # Hulls (the default) keep one mesh, in another cache entry; pieces come from the cache.
    hull = _collision_files(robot_files.drake_urdf(_toy_with_pieces(tmp_path / "h", "hull")))
    assert len(hull["link2"]) == 1
    assert robot_files.drake_urdf(pieces) == urdf


def test_an_unknown_collision_meshes_value_is_named(tmp_path):
    with pytest.raises(ConfigError, match="collision_meshes must be one of hull, pieces"):
        _toy_with_pieces(tmp_path, "decomposed")
