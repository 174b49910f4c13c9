"""drake_sim.systems.estimation.match_updates: a match level kept up to date equals one made
again whole from the grid, also where walls are seen through and stop being occupied."""

import numpy as np
import pytest

import drake_sim.systems.estimation.match_updates as mut
from drake_sim.systems.estimation.occupancy_grid import LogOddsGrid
from drake_sim.systems.estimation.scan_matcher import MatchMap
from tests import slam_helpers as helpers


@pytest.mark.parametrize("field", [1.0, 0.0])
def test_a_level_brought_up_to_date_matches_one_made_again_whole(field):
    """``update_level`` after each map update: the same values and gradients as
    ``from_grid`` on the whole grid wherever a point can weigh (seen cells and their
    neighbours), while the level grows as the robot sees more of the room."""
    truth = helpers.drive(helpers.ROOM_ROUTE, helpers.ROOM_START)
    ranges, angles = helpers.lidar_scans(helpers.room(), truth, seed=0)
    grid = LogOddsGrid(resolution=0.05, size=(30.0, 30.0), origin=(-15.0, -15.0), hit_offset=0.5)
    grid.track_changes = True
    level, shapes = None, set()
    rng = np.random.default_rng(0)
    for k in range(0, len(truth), 9):
        grid.insert_scan(truth[k], ranges[k], angles, 3.5)
        changes, box = grid.take_changes(), grid.take_changed_box()
        assert box is not None and grid.take_changed_box() is None
        if level is None:
            level = MatchMap.from_grid(grid, field=field)
        else:
            level = mut.update_level(level, grid, changes, box, field=field)
        shapes.add(level.values.shape)
        whole = MatchMap.from_grid(grid, field=field)
        rows, cols = np.nonzero(whole.known)
        # Points off the cell centres (where a one-sided gradient may pick either side).
        u, v = rng.uniform(0.1, 0.9, (2, len(rows)))
        xy = np.stack(
            [
                whole.origin[0] + (cols - 1 + u) * whole.resolution,
                whole.origin[1] + (rows - 1 + v) * whole.resolution,
            ],
            -1,
        )
        np.testing.assert_array_equal(level.is_known(xy), whole.is_known(xy))
        expected, expected_gradient = whole.interpolate(xy)
        value, gradient = level.interpolate(xy)
        np.testing.assert_allclose(value, expected, rtol=0, atol=1e-12)
        np.testing.assert_allclose(gradient, expected_gradient, rtol=0, atol=1e-10)
    assert len(shapes) > 1  # it grew


def test_a_wall_seen_through_leaves_the_field_where_it_was():
    """Cells that stop being occupied (a door opened: beams now pass where a wall was) take the
    field down with them, as a level made again whole has it."""
    grid = LogOddsGrid(resolution=0.05, size=(10.0, 10.0), origin=(-5.0, -5.0))
    grid.track_changes = True
    angles = np.linspace(-0.3, 0.3, 40)
    for _ in range(3):  # a wall 2 m ahead
        grid.insert_scan((0.0, 0.0, 0.0), np.full(40, 2.0 / np.cos(angles)), angles, 3.5)
    grid.take_changes(), grid.take_changed_box()
    level = MatchMap.from_grid(grid, field=1.0)
    for _ in range(12):  # ... now gone: the beams reach 3 m
        grid.insert_scan((0.0, 0.0, 0.0), np.full(40, 3.0 / np.cos(angles)), angles, 3.5)
    changes = grid.take_changes()
    assert changes[1].size > 0  # cells stopped being occupied
    level = mut.update_level(level, grid, changes, grid.take_changed_box(), field=1.0)
    whole = MatchMap.from_grid(grid, field=1.0)
    xy = np.stack([np.linspace(0.5, 3.2, 200), np.linspace(-0.4, 0.4, 200)], -1)
    np.testing.assert_allclose(level.interpolate(xy)[0], whole.interpolate(xy)[0], atol=1e-12)
    assert level.interpolate(np.array([[2.0, 0.0]]))[0][0] < 0.01  # the old wall's place
