"""An arena in a plant (drake_sim.worlds.arena_world): the SDF parses, everything is welded, and
the collision geometry that SceneGraph holds agrees with the ground-truth grid cell by cell."""

import numpy as np
import pytest
from pydrake.geometry import Role
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

import drake_sim.worlds.arena_world as mut
from drake_sim.base.resources import cache_dir
from drake_sim.worlds.arena import arena_footprints, arena_grid, load_arena, shipped_arenas

SCAN_HEIGHT = 0.17  # m: the TurtleBot3 lidar's scan plane above the floor.

MIXED = """
size: [4.0, 3.0]
wall: {height: 0.3, thickness: 0.07}
obstacles:
  - {box: {size: [0.5, 0.3, 0.3], position: [0.8, 0.4], yaw: 37}}
  - {box: {size: [0.4, 0.4, 0.1], position: [-0.8, 0.6]}}          # below the scan plane
  - {cylinder: {radius: 0.18, height: 0.4, position: [-0.7, -0.6]}}
  - {wall: {from: [0.5, -1.5], to: [1.3, -0.6], thickness: 0.09, height: 0.5}}
start: {x: -1.4, y: 0.0, yaw: 0}
"""


def _plant_with(arena, name="arena"):
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.001)
    instance = mut.add_arena(plant, arena, name=name)
    plant.Finalize()
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    query = scene_graph.get_query_output_port().Eval(scene_graph.GetMyContextFromRoot(context))
    return plant, instance, query


def _arena(tmp_path, text=MIXED):
    path = tmp_path / "mixed.yaml"
    path.write_text(text)
    return load_arena(path)


def test_the_arena_is_static_with_a_link_per_wall_and_obstacle(tmp_path):
    arena = _arena(tmp_path)
    plant, instance, query = _plant_with(arena)
    assert plant.GetModelInstanceName(instance) == "arena"
    assert plant.num_positions() == 0 and plant.num_velocities() == 0  # all welded
    names = [plant.get_body(b).name() for b in plant.GetBodyIndices(instance)]
    assert names == ["ground"] + [f.name for f in arena_footprints(arena)]
    inspector = query.inspector()
    proximity = inspector.GetAllGeometryIds(Role.kProximity)
    assert len(proximity) == len(names)
    assert len(inspector.GetAllGeometryIds(Role.kIllustration)) == len(names)
    # Perception too, so that depth cameras (a render-based lidar) see every geometry.
    assert len(inspector.GetAllGeometryIds(Role.kPerception)) == len(names)
    ground = plant.GetCollisionGeometriesForBody(plant.GetBodyByName("ground", instance))[0]
    friction = inspector.GetProximityProperties(ground).GetProperty("material", "coulomb_friction")
    assert (friction.static_friction(), friction.dynamic_friction()) == mut.GROUND_FRICTION


def _assert_grid_agrees(query, grid, cells=None) -> int:
    """At each cell (row, col) of ``cells`` (every known cell when None), at the scan height,
    SceneGraph's signed distance is negative exactly where ``grid`` is occupied (a centre
    exactly on a face is skipped: the grid counts it inside by convention). Returns the number
    of occupied cells checked."""
    xs, ys = (np.asarray(v) for v in grid.centres())
    if cells is None:
        cells = zip(*np.nonzero(grid.cells >= 0), strict=True)
    occupied = 0
    for r, c in cells:
        p = np.array([xs[r, c], ys[r, c], SCAN_HEIGHT])
        distances = [d.distance for d in query.ComputeSignedDistanceToPoint(p, 1e-5)]
        if distances and abs(min(distances)) < 1e-6:
            continue
        inside = bool(distances) and min(distances) < 0
        assert inside == (grid.cells[r, c] == 100), (grid.resolution, p)
        occupied += inside
    return occupied


def test_collision_geometry_agrees_with_the_grid_at_every_cell(tmp_path):
    """SceneGraph's signed distance at every cell centre, at the scan height, is negative
    exactly where the grid (restricted to geometry at least that tall) is occupied."""
    arena = _arena(tmp_path)
    _, _, query = _plant_with(arena)
    for resolution in (0.05, 0.1):
        grid = arena_grid(arena, resolution, height=SCAN_HEIGHT)
        occupied = _assert_grid_agrees(query, grid)
        assert occupied > 0.05 * np.sum(grid.cells >= 0)
        # The low box is in the plant but below the scan plane, so neither sees it there.
        r, c = grid.cell_of(np.array([-0.8, 0.6]))
        assert grid.cells[r, c] == 0
        assert arena_grid(arena, resolution).cells[r, c] == 100


@pytest.mark.parametrize("path", shipped_arenas(), ids=lambda p: p.stem)
def test_every_shipped_arena_agrees_with_its_grid(path):
    arena = load_arena(path)
    _, _, query = _plant_with(arena)
    grid = arena_grid(arena, 0.1, height=SCAN_HEIGHT)
    rows, cols = np.nonzero(grid.cells >= 0)
    rng = np.random.default_rng(7)
    picked = rng.choice(len(rows), size=min(1500, len(rows)), replace=False)
    _assert_grid_agrees(query, grid, ((rows[k], cols[k]) for k in picked))


def test_the_ground_is_the_floor(tmp_path):
    _, _, query = _plant_with(_arena(tmp_path))
    below = query.ComputeSignedDistanceToPoint(np.array([0.0, -0.2, -0.01]), 0.0)
    assert len(below) == 1 and below[0].distance == pytest.approx(-0.01)
    above = query.ComputeSignedDistanceToPoint(np.array([0.0, -0.2, 0.02]), 0.03)
    assert [d.distance for d in above] == pytest.approx([0.02])


def test_the_sdf_is_cached_by_content(tmp_path):
    arena = _arena(tmp_path)
    first = mut.arena_sdf_file(arena)
    assert first.parent == cache_dir() / "arenas" and first.read_text() == mut.arena_sdf(arena)
    assert mut.arena_sdf_file(arena) == first
    arena.obstacles[0].box.yaw = 10.0
    assert mut.arena_sdf_file(arena) != first
    renamed = mut.arena_sdf(arena, name="other")
    assert '<model name="other">' in renamed and "<static>true</static>" in renamed


def test_two_arenas_in_one_plant_need_two_names(tmp_path):
    arena = _arena(tmp_path)
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlantSceneGraph(builder, 0.001)
    a = mut.add_arena(plant, arena)
    b = mut.add_arena(plant, arena, name="second")
    assert plant.GetModelInstanceName(b) == "second" and a != b


def test_a_large_arena_anchors_its_obstacles_on_the_world_body(tmp_path):
    """More than MAX_LINKS obstacles (a map's world): the ground stays a link, the rest are
    geometry of the world body, with the same names, and the grid still agrees with them."""
    posts = "".join(
        f"  - {{box: {{size: [0.1, 0.1, 0.3], position: [{-2.0 + 0.2 * (i % 20):.1f}, "
        f"{-1.0 + 0.2 * (i // 20):.1f}]}}}}\n"
        for i in range(mut.MAX_LINKS + 20)
    )
    text = f"size: [5.0, 3.0]\nobstacles:\n{posts}start: {{x: 2.2, y: 1.2, yaw: 0}}\n"
    arena = _arena(tmp_path, text)
    plant, instance, query = _plant_with(arena)
    names = [plant.get_body(b).name() for b in plant.GetBodyIndices(instance)]
    assert names[0] == "ground" and len(names) == 5  # the ground and the outer walls
    inspector = query.inspector()
    anchored = inspector.GetGeometries(inspector.world_frame_id(), Role.kProximity)
    expected = {f.name for f in arena_footprints(arena)[4:]}
    assert {inspector.GetName(g).split("::")[-1] for g in anchored} == expected
    _assert_grid_agrees(query, arena_grid(arena, 0.05, height=SCAN_HEIGHT))
