"""The real map_server maps of ``shared/real_ros/maps`` (beside the checkout; skipped, saying
why, when it is not there) load as nav2's map_server loads them."""

from pathlib import Path

import numpy as np
import pytest

from drake_sim.base.map_files import MapFileError, load_map

MAPS = Path(__file__).resolve().parents[4] / "shared" / "real_ros" / "maps"


@pytest.fixture(scope="module")
def maps():
    if not MAPS.is_dir():
        pytest.skip(f"no real ROS maps at {MAPS} (third-party files, not in the repository)")
    return sorted(MAPS.glob("*/*.yaml"))


def test_every_real_map_loads_or_names_its_missing_image(maps, caplog):
    loaded = 0
    for path in maps:
        try:
            grid = load_map(path)
        except MapFileError as e:  # nav2's empty_room.yaml names an image it does not ship
            assert "no such map image" in str(e) and "\n" not in str(e), path
            continue
        loaded += 1
        assert grid.cells.size > 0 and grid.resolution > 0
        assert set(np.unique(grid.cells)) <= {-1, *range(0, 101)}
    assert loaded >= len(maps) - 1
    ignored = [r.getMessage() for r in caplog.records if "ignored keys" in r.getMessage()]
    assert all("map_type" in message for message in ignored)


def test_the_speed_mask_reads_as_nav2_reads_it(maps):
    path = MAPS / "nav2_system_tests" / "speed_mask.yaml"
    if path not in maps:
        pytest.skip("no speed_mask.yaml among the real maps")
    values, counts = np.unique(load_map(path).cells, return_counts=True)
    assert dict(zip(values.tolist(), counts.tolist(), strict=True)) == {
        0: 8690,
        19: 138595,
        50: 171,
    }
