"""Tests for the street world (models/worlds/ddrive.world.sdf) and the generated models."""

import re
import subprocess
import sys

import numpy as np
import pytest
from pydrake.geometry import Convex, HalfSpace, Mesh, Role
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.multibody.tree import CalcSpatialInertia, ModelInstanceIndex
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from diagrams.ddrive_world import add_ground
from diagrams.world_scenario import GroundConfig
from drake_sim.base.resources import make_parser, models_dir, package_uri
from drake_sim.tools import generate_models as mut

WORLD_URL = package_uri("worlds/ddrive.world.sdf")
# The robot's corridor above the street surface (world frame, m); the ground's top is z = 0.
CORRIDOR_MIN = np.array([-4.5, -1.2, 1e-3])
CORRIDOR_MAX = np.array([4.5, 1.2, 1.5])  # m


def _build(contact_model="hydroelastic_with_fallback"):
    """Returns (diagram, plant, scene_graph) holding the world, finalised at 2 ms."""
    builder = DiagramBuilder()
    config = MultibodyPlantConfig(time_step=2e-3, contact_model=contact_model)
    plant, scene_graph = AddMultibodyPlant(config, builder)
    add_ground(plant, GroundConfig())
    make_parser(plant).AddModels(url=WORLD_URL)
    plant.Finalize()
    return builder.Build(), plant, scene_graph


@pytest.fixture(scope="module")
def world():
    return _build()


def _names(plant):
    """Returns the names of all model instances in ``plant``."""
    count = plant.num_model_instances()
    return [plant.GetModelInstanceName(ModelInstanceIndex(i)) for i in range(count)]


def _instances(plant, prefix):
    """Returns the names of the model instances whose name starts with ``prefix``."""
    return [n for n in _names(plant) if n.startswith(prefix)]


def _overlaps_corridor(lo, hi):
    """Whether the axis-aligned box [lo, hi] (world frame, m) overlaps the corridor."""
    return bool(np.all(lo < CORRIDOR_MAX) and np.all(hi > CORRIDOR_MIN))


def test_world_has_every_model(world):
    _, plant, _ = world
    assert plant.is_finalized() and plant.time_step() == 2e-3
    assert len(_instances(plant, "barrier_")) >= 2
    assert len(_instances(plant, "cardboard_box_")) >= 2
    others = _instances(plant, "traffic_cone_") + _instances(plant, "trash_can_")
    assert len(others) >= 2 and {n.rsplit("_", 1)[0] for n in others} == {
        "traffic_cone",
        "trash_can",
    }
    assert "asphalt_ground" in _names(plant) and "street_markings" in _names(plant)
    free = {
        plant.GetModelInstanceName(plant.get_body(b).model_instance())
        for b in plant.GetFloatingBaseBodies()
    }
    assert set(_instances(plant, "cardboard_box_")) <= free
    assert not any(n.startswith("barrier_") for n in free)


def test_barrier_collision_matches_real_profile(world):
    _, plant, scene_graph = world
    inspector = scene_graph.model_inspector()
    body = plant.GetBodyByName("body", plant.GetModelInstanceByName("barrier_north_1"))
    ids = inspector.GetGeometries(plant.GetBodyFrameIdOrThrow(body.index()), Role.kProximity)
    assert len(ids) >= 2
    vertices = []
    for geometry_id in ids:
        shape = inspector.GetShape(geometry_id)
        assert isinstance(shape, Convex)
        hull = inspector.GetConvexHull(geometry_id)
        X_BG = inspector.GetPoseInFrame(geometry_id)
        p_GV = np.array([hull.vertex(i) for i in range(hull.num_vertices())]).T
        vertices.append(X_BG @ p_GV)
    p = np.hstack(vertices).T
    height = p[:, 2].max() - p[:, 2].min()
    assert height == pytest.approx(0.813, abs=0.01)
    assert np.ptp(p[p[:, 2] < 1e-6, 1]) == pytest.approx(0.61, abs=0.01)
    assert np.ptp(p[p[:, 2] > p[:, 2].max() - 1e-6, 1]) == pytest.approx(0.152, abs=0.01)
    assert np.ptp(p[:, 0]) == pytest.approx(3.0, abs=0.01)
    # The slopes: 55 degrees from the reveal to 13 in, then 84 degrees to the top.
    profile = mut.JerseyBarrierSpec().profile()
    for a, b, degrees in ((2, 3, 55.0), (3, 4, 84.0)):
        rise, run = profile[b, 1] - profile[a, 1], abs(profile[b, 0] - profile[a, 0])
        assert np.degrees(np.arctan2(rise, run)) == pytest.approx(degrees, abs=0.5)


def test_barrier_inertia_is_concrete(world):
    _, plant, _ = world
    body = plant.GetBodyByName("body", plant.GetModelInstanceByName("barrier_south_2"))
    expected = CalcSpatialInertia(
        Mesh(str(models_dir() / "jersey_barrier/jersey_barrier.obj")), 2400.0
    )
    assert body.default_mass() == pytest.approx(expected.get_mass(), rel=1e-3)
    assert body.default_com() == pytest.approx(expected.get_com(), abs=1e-4)


def test_generated_files_are_up_to_date(tmp_path):
    assert mut.differences(mut.generate(models_dir())) == []
    result = subprocess.run(
        [sys.executable, "-m", "drake_sim.tools.generate_models", "--check"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    # A fresh folder is reported stale, then matches once written.
    files = mut.generate(tmp_path)
    assert len(mut.differences(files)) == len(files)
    mut.write(files)
    assert mut.differences(files) == []


def test_generated_files_are_small():
    files = [p for p in models_dir().rglob("*") if p.suffix in (".obj", ".mtl", ".png")]
    assert sum(p.stat().st_size for p in files) < 2_000_000
    for path, data in mut.generate(models_dir()).items():
        if isinstance(data, np.ndarray):
            assert data.dtype == np.uint8 and max(data.shape[:2]) <= 256, path


def test_models_use_only_package_uris():
    absolute = re.compile(r"file://|(?<![\w:/.])/(home|work|tmp|usr|opt|root|Users)/|[A-Z]:\\")
    for path in models_dir().rglob("*"):
        if path.suffix not in (".sdf", ".urdf", ".xacro", ".mtl", ".obj", ".xml", ".yaml"):
            continue
        text = path.read_text()
        assert not absolute.search(text), path
        if path.suffix == ".sdf":
            for uri in re.findall(r"<uri>\s*([^<]*?)\s*</uri>", text):
                assert uri.startswith("package://drake_sim_models/"), (path, uri)


@pytest.mark.parametrize("contact_model", ["point", "hydroelastic_with_fallback"])
def test_free_bodies_rest_still(contact_model):
    diagram, plant, _ = _build(contact_model)
    simulator = Simulator(diagram)
    context = plant.GetMyContextFromRoot(simulator.get_mutable_context())
    bodies = [plant.get_body(b) for b in sorted(plant.GetFloatingBaseBodies())]
    assert len(bodies) >= 3
    p0 = [plant.EvalBodyPoseInWorld(context, b).translation().copy() for b in bodies]
    simulator.AdvanceTo(1.0)
    for body, p_start in zip(bodies, p0, strict=True):
        moved = np.linalg.norm(plant.EvalBodyPoseInWorld(context, body).translation() - p_start)
        assert moved < 0.02, plant.GetModelInstanceName(body.model_instance())


def test_corridor_is_free_of_collision_geometry(world):
    diagram, plant, scene_graph = world
    context = diagram.CreateDefaultContext()
    query = scene_graph.get_query_output_port().Eval(scene_graph.GetMyContextFromRoot(context))
    inspector = query.inspector()
    checked = 0
    for geometry_id in inspector.GetAllGeometryIds(Role.kProximity):
        obb = inspector.GetObbInGeometryFrame(geometry_id)
        if obb is None:
            assert isinstance(inspector.GetShape(geometry_id), HalfSpace)
            continue
        X_WG = query.GetPoseInWorld(geometry_id)
        X_WB = X_WG @ obb.pose()
        signs = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1)
        corners = X_WB @ (signs * obb.half_width()[:, None])
        lo, hi = corners.min(axis=1), corners.max(axis=1)
        assert not _overlaps_corridor(lo, hi), inspector.GetName(geometry_id)
        checked += 1
    assert checked > 10
    # The check itself catches a small object on the line, and not one resting beside it.
    assert _overlaps_corridor(np.array([3.0, -0.1, 0.0]), np.array([3.2, 0.1, 0.2]))
    assert not _overlaps_corridor(np.array([3.0, 1.3, 0.0]), np.array([3.2, 1.5, 0.2]))
