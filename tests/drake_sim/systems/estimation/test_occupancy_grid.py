"""drake_sim.systems.estimation.occupancy_grid: log-odds updates, ray tracing, map scores."""

import math

import numpy as np
import pytest

import drake_sim.systems.estimation.occupancy_grid as mut
from drake_sim.base.map_files import OccupancyMap
from tests import slam_helpers as helpers


def make_grid(**kwargs) -> mut.LogOddsGrid:
    return mut.LogOddsGrid(resolution=0.05, size=(10.0, 8.0), origin=(-5.0, -4.0), **kwargs)


def value(grid, x, y) -> float:
    row = int(math.floor((y - grid.origin[1]) / grid.resolution))
    col = int(math.floor((x - grid.origin[0]) / grid.resolution))
    return float(grid.log_odds[row, col])


def test_one_beam_marks_its_end_occupied_and_its_path_free():
    dut = make_grid()
    dut.insert_scan((0.0, 0.0, 0.0), [2.0], [0.0], 3.5)
    assert value(dut, 2.01, 0.01) == pytest.approx(dut.l_hit)
    for x in np.arange(0.01, 1.95, 0.05):  # every cell on the way, once
        assert value(dut, x, 0.01) == pytest.approx(dut.l_miss), x
    assert value(dut, 2.1, 0.01) == 0.0  # behind the hit: unseen
    assert value(dut, 1.0, 0.1) == 0.0  # beside the beam: unseen
    assert dut.version == 1


def test_beam_directions_follow_the_sensor_yaw():
    dut = make_grid()
    dut.insert_scan((1.0, -1.0, math.pi / 2), [1.02, 1.02], [0.0, math.pi / 2], 3.5)
    assert value(dut, 1.01, 0.01) > 0  # straight ahead = +y in the world
    assert value(dut, -0.01, -0.99) > 0  # 90 degrees to the left = -x


def test_no_return_clears_to_range_max_and_bad_beams_are_ignored():
    dut = make_grid()
    ranges = [np.inf, np.nan, 0.05, 1.0]
    angles = [0.0, math.pi / 2, math.pi, -math.pi / 2]
    dut.insert_scan((0.0, 0.0, 0.0), ranges, angles, 3.0, range_min=0.12, mask=[1, 1, 1, 0])
    assert value(dut, 2.96, 0.01) < 0 and value(dut, 3.04, 0.01) == 0.0  # free up to 3 m
    assert value(dut, 0.01, 1.0) == 0.0  # NaN: no information
    assert value(dut, -0.5, 0.01) == 0.0  # shorter than range_min: ignored
    assert value(dut, 0.01, -1.01) == 0.0  # masked out
    limited = make_grid()
    limited.insert_scan((0.0, 0.0, 0.0), [np.inf], [0.0], 3.0, max_free_range=1.0)
    assert value(limited, 0.96, 0.01) < 0 and value(limited, 1.5, 0.01) == 0.0


def test_a_cell_hit_and_crossed_in_one_scan_counts_as_hit_once():
    dut = make_grid()
    # Two beams end in the same cell, a third crosses it on its way further.
    ranges = [1.02, 1.03, 2.0]
    angles = [0.0, 0.0, 0.0]
    dut.insert_scan((0.0, 0.0, 0.0), ranges, angles, 3.5)
    assert value(dut, 1.01, 0.01) == pytest.approx(dut.l_hit)


def wall_on_a_cell_edge(**kwargs) -> mut.LogOddsGrid:
    """A grid of 10 scans of a wall whose face is the line x = 1 (a cell edge), seen square on
    with 1 cm range noise: half the end points fall short of the edge."""
    dut = make_grid(**kwargs)
    rng = np.random.default_rng(0)
    angles = np.radians(np.linspace(-10.0, 10.0, 41))
    for _ in range(10):
        ranges = 1.0 / np.cos(angles) + rng.normal(0.0, 0.01, angles.shape)
        dut.insert_scan((0.0, 0.0, 0.0), ranges, angles, 3.5)
    return dut


def test_hits_half_a_cell_beyond_the_end_mark_the_wall_cell_only():
    # The wall is one cell thick, the cell behind the face (as arena_grid rasterises it).
    dut = wall_on_a_cell_edge(hit_offset=0.5)
    for y in np.arange(-0.15, 0.16, 0.05):
        assert value(dut, 1.01, y) > 0, y  # the wall's cell: occupied
        assert value(dut, 0.99, y) < 0, y  # the free cell in front of it: free


def test_hits_in_the_end_cell_thicken_a_wall_on_a_cell_edge():
    dut = wall_on_a_cell_edge()  # hector_slam's marking, what the scan matcher reads
    in_front = [value(dut, 0.99, y) for y in np.arange(-0.15, 0.16, 0.05)]
    assert np.mean(np.array(in_front) > 0) > 0.5


def test_log_odds_are_clamped():
    dut = make_grid(clamp=2.0)
    for _ in range(10):
        dut.insert_scan((0.0, 0.0, 0.0), [1.0], [0.0], 3.5)
    assert value(dut, 1.01, 0.01) == pytest.approx(2.0)
    assert value(dut, 0.51, 0.01) == pytest.approx(-2.0)
    assert dut.probability()[0, 0] == 0.5


def test_points_off_the_grid_are_dropped():
    dut = mut.LogOddsGrid(resolution=0.1, size=(1.0, 1.0), origin=(0.0, 0.0))
    dut.insert_scan((0.5, 0.5, 0.0), [5.0, np.inf], [0.0, math.pi], 6.0)
    assert dut.log_odds[5, 9] < 0 and dut.log_odds[5, 0] < 0 and (dut.log_odds >= -1).all()


def test_to_occupancy_map_is_trinary_and_cropped():
    dut = make_grid()
    dut.insert_scan((0.0, 0.0, 0.0), [1.0, 1.0], [0.0, math.pi / 2], 3.5)
    full = dut.to_occupancy_map(crop=False)
    assert full.shape == dut.shape and full.origin == (-5.0, -4.0, 0.0)
    assert set(np.unique(full.cells)) == {-1, 0, 100}
    cropped = dut.to_occupancy_map(margin=2)
    assert cropped.shape == (21 + 4, 21 + 4)  # rows y 0..1, cols x 0..1, plus margins
    assert cropped.value_at([[1.01, 0.01]])[0] == 100
    assert cropped.value_at([[0.5, 0.01]])[0] == 0
    assert cropped.value_at([[0.5, 0.5]])[0] == -1
    assert mut.LogOddsGrid(resolution=0.1, size=(1, 1), origin=(0, 0)).to_occupancy_map().shape == (
        10,
        10,
    )


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(resolution=0.0),
        dict(p_hit=0.5),
        dict(p_miss=0.6),
        dict(clamp=0.0),
        dict(hit_offset=1.0),
        dict(hit_offset=-0.1),
    ],
)
def test_bad_parameters(kwargs):
    args = dict(resolution=0.05, size=(1.0, 1.0), origin=(0.0, 0.0)) | kwargs
    with pytest.raises(ValueError):
        mut.LogOddsGrid(**args)


def test_scans_from_true_poses_map_the_room():
    world = helpers.room()
    truth = world.truth(0.05)
    poses = helpers.drive(helpers.ROOM_ROUTE, helpers.ROOM_START)[::8]
    ranges, angles = helpers.lidar_scans(world, poses, seed=4)
    dut = make_grid()
    for pose, scan in zip(poses, ranges, strict=True):
        dut.insert_scan(pose, scan, angles, 3.5)
    result = dut.to_occupancy_map()
    assert mut.occupancy_iou(result, truth) >= 0.95
    assert mut.known_fraction(result, truth) >= 0.97
    assert mut.known_fraction(dut.to_occupancy_map(crop=False), truth) == mut.known_fraction(
        result, truth
    )


def box_world() -> OccupancyMap:
    """A 2 m square room (walls 2 cells thick) with a 0.4 m box, at 0.05 m."""
    cells = np.zeros((40, 40), np.int8)
    cells[:2], cells[-2:], cells[:, :2], cells[:, -2:] = 100, 100, 100, 100
    cells[10:18, 20:28] = 100
    return OccupancyMap(cells, 0.05, (-1.0, -1.0, 0.0))


def shifted(grid: OccupancyMap, cells: int) -> OccupancyMap:
    x, y, yaw = grid.origin
    return OccupancyMap(grid.cells, grid.resolution, (x + cells * grid.resolution, y, yaw))


def test_iou_of_the_truth_with_itself_and_shifted_copies():
    truth = box_world()
    free, surface = mut.observable(truth)
    assert free.sum() == 36 * 36 - 64 and surface.sum() == 4 * 37 + 28  # not the box's inside
    surface_only = OccupancyMap(np.where(surface, 100, np.where(free, 0, -1)), 0.05)
    surface_only.origin = truth.origin
    assert mut.occupancy_iou(surface_only, truth) == 1.0
    assert mut.occupancy_iou(shifted(surface_only, 1), truth) > 0.95  # within the tolerance
    assert mut.occupancy_iou(shifted(surface_only, 1), truth, tolerance_cells=0) < 0.6
    assert mut.occupancy_iou(shifted(surface_only, 4), truth) < 0.5
    empty = OccupancyMap(np.full((40, 40), -1), 0.05, truth.origin)
    assert mut.occupancy_iou(empty, truth) == 0.0


def test_iou_counts_spurious_and_missing_walls():
    truth = box_world()
    _, surface = mut.observable(truth)
    cells = np.where(surface, 100, 0)
    extra = cells.copy()
    extra[25, 5:35] = 100  # a wall that is not there: 30 cells
    score = mut.occupancy_iou(OccupancyMap(extra, 0.05, truth.origin), truth)
    assert score == pytest.approx((2 * surface.sum()) / (2 * surface.sum() + 30), abs=0.02)
    missing = cells.copy()
    missing[10:18, 20:28] = 0  # the box is not mapped
    assert mut.occupancy_iou(OccupancyMap(missing, 0.05, truth.origin), truth) < 0.95


def test_scores_compare_maps_of_other_resolutions_and_origins():
    truth = box_world()
    fine = OccupancyMap(np.kron(truth.cells, np.ones((2, 2), np.int8)), 0.025, truth.origin)
    assert mut.occupancy_iou(fine, truth) > 0.95
    assert mut.known_fraction(fine, truth) == 1.0
    _, surface = mut.observable(fine)
    walls_only = OccupancyMap(np.where(surface, 100, np.where(fine.free(), 0, -1)), 0.025)
    walls_only.origin = fine.origin
    assert mut.occupancy_iou(walls_only, truth) > 0.95


def test_known_fraction():
    truth = box_world()
    assert mut.known_fraction(truth, truth) == 1.0
    half = truth.cells.copy()
    half[:, :20] = -1
    assert mut.known_fraction(OccupancyMap(half, 0.05, truth.origin), truth) == pytest.approx(
        0.5, abs=0.06
    )
    elsewhere = OccupancyMap(truth.cells, 0.05, (10.0, 10.0, 0.0))
    assert mut.known_fraction(elsewhere, truth) == 0.0


def test_the_changed_box_holds_every_cell_changed_since_it_was_taken():
    grid = mut.LogOddsGrid(resolution=0.1, size=(10.0, 10.0), origin=(-5.0, -5.0))
    assert grid.take_changed_box() is None
    before = grid.log_odds.copy()
    grid.insert_scan((0.0, 0.0, 0.0), [1.0], [0.0], 3.5)
    grid.insert_scan((-2.0, 1.0, 0.0), [0.5], [math.pi / 2], 3.5)
    box = grid.take_changed_box()
    rows, cols = np.nonzero(grid.log_odds != before)
    assert box == [rows.min(), rows.max(), cols.min(), cols.max()]
    assert grid.take_changed_box() is None
    assert grid.known_box == box  # the first changes are all the known cells


def test_tracked_changes_list_the_cells_that_became_occupied_free_or_seen():
    grid = mut.LogOddsGrid(resolution=0.1, size=(10.0, 10.0), origin=(-5.0, -5.0))
    grid.insert_scan((0.0, 0.0, 0.0), [1.0], [0.0], 3.5)
    assert all(part.size == 0 for part in grid.take_changes())  # off: nothing kept
    grid.track_changes = True
    before = grid.log_odds.copy()
    grid.insert_scan((0.0, 0.0, 0.0), [2.0], [0.0], 3.5)  # the wall at 1 m is now seen through
    for _ in range(3):
        grid.insert_scan((0.0, 0.0, 0.0), [2.0], [0.0], 3.5)
    became, stopped, seen = grid.take_changes()
    after = grid.log_odds.ravel()
    flat = before.ravel()
    np.testing.assert_array_equal(np.unique(became), np.nonzero((flat <= 0) & (after > 0))[0])
    np.testing.assert_array_equal(np.unique(stopped), np.nonzero((flat > 0) & (after <= 0))[0])
    np.testing.assert_array_equal(np.unique(seen), np.nonzero((flat == 0) & (after != 0))[0])
    assert stopped.size == 1 and all(part.size == 0 for part in grid.take_changes())


def test_clear_forgets_every_scan_and_the_same_scans_draw_the_same_grid_again():
    grid = make_grid()
    grid.track_changes = True
    scans = [((0.0, 0.0, 0.0), [2.0, 1.0]), ((1.0, 0.5, 0.3), [1.5, np.inf])]
    for pose, ranges in scans:
        grid.insert_scan(pose, ranges, [0.0, 1.0], 3.5)
    drawn, version = grid.log_odds.copy(), grid.version
    grid.clear()
    assert not grid.log_odds.any() and grid.known_box is None and grid.version == version + 1
    assert grid.take_changed_box() is None and all(p.size == 0 for p in grid.take_changes())
    for pose, ranges in scans:
        grid.insert_scan(pose, ranges, [0.0, 1.0], 3.5)
    np.testing.assert_array_equal(grid.log_odds, drawn)


def test_extend_adds_unknown_cells_and_keeps_the_map_where_it_was():
    grid = make_grid()
    grid.insert_scan((0.0, 0.0, 0.0), [2.0], [0.0], 3.5)
    before = grid.to_occupancy_map(crop=False)
    grid.take_changed_box()
    grid.extend(4, 2, 6, 0)
    assert grid.shape == (160 + 6, 200 + 6) and grid.origin == (-5.3, -4.2)
    after = grid.to_occupancy_map(crop=False)
    assert np.array_equal(after.cells[4:-2, 6:], before.cells)
    assert (after.cells[:4] == -1).all() and (after.cells[:, :6] == -1).all()
    assert value(grid, 2.0, 0.0) > 0 and value(grid, 1.0, 0.0) < 0
    rows, cols = np.nonzero(after.cells >= 0)  # the known box moved with the cells
    assert grid.known_box == [rows.min(), rows.max(), cols.min(), cols.max()]
    assert grid.take_changes()[0].size == 0  # flat indices of the old shape: dropped
    grid.insert_scan((-5.2, -4.1, 0.0), [0.5], [0.0], 3.5)  # in the new cells
    assert value(grid, -4.7, -4.1) > 0


def test_grids_grow_to_cover_points_beyond_them_on_one_lattice():
    grids = [
        mut.LogOddsGrid(resolution=r, size=(4.0, 4.0), origin=(-2.0, -2.0))
        for r in (0.025, 0.05, 0.1, 0.2)
    ]
    assert not mut.grow_to_cover(grids, [[1.5, -1.5], [-1.7, 1.7]], 0.2)  # inside: unchanged
    assert grids[1].shape == (80, 80) and grids[1].origin == (-2.0, -2.0)
    assert mut.grow_to_cover(grids, [[2.5, 0.0]], 0.2)
    for grid in grids:
        # Right: 0.7 m lacking (with a step's margin), a quarter of the side added (1 m, 5
        # steps of 0.2); the other sides as they were.
        assert grid.origin == (-2.0, -2.0)
        assert grid.shape[1] * grid.resolution == pytest.approx(5.0)
        assert grid.shape[0] * grid.resolution == pytest.approx(4.0)
    assert mut.grow_to_cover(grids, [[0.0, -2.1]], 0.2)  # just beyond: at least a quarter
    for grid in grids:
        assert grid.origin == pytest.approx((-2.0, -3.0))
        assert grid.shape[0] * grid.resolution == pytest.approx(5.0)
    assert mut.grow_to_cover(grids, [[6.05, 0.0]], 0.2)  # far beyond: as far as it needs
    assert grids[0].shape[1] * grids[0].resolution == pytest.approx(8.4)  # to 6.4 > 6.25
    assert not mut.grow_to_cover(grids, np.zeros((0, 2)), 0.2)
