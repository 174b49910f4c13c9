"""drake_sim.systems.estimation.slam_config: the SLAM's defaults, its YAML file, and every bad
value named in one line."""

import numpy as np
import pytest

import drake_sim.systems.estimation.slam_config as mut
from drake_sim.base.errors import ConfigError


def test_defaults_and_config_file(tmp_path):
    config = mut.SlamConfig()
    config.check()
    assert (config.resolution, config.levels, config.map_size) == (0.05, 3, 30.0)
    path = tmp_path / "slam.yaml"
    path.write_text("map_update_distance: 0.3\niterations: [5, 4, 3, 2]\n")
    loaded = mut.load_slam_config(path)
    assert loaded.map_update_distance == 0.3 and loaded.iterations == [5, 4, 3, 2]
    assert loaded.p_hit == config.p_hit


@pytest.mark.parametrize(
    "text, match",
    [
        ("resolution: -0.05", "'resolution' must be positive"),
        ("resolution: .nan", "'resolution' must be finite"),
        ("p_hit: 0.4", "'p_hit' must be in"),
        ("p_miss: 0.7", "'p_miss' must be in"),
        ("levels: 3\niterations: [4, 4]", "'iterations' needs 4 counts"),
        ("levels: 0", "'levels' must be at least 1"),
        ("prior_weight: [1.0, 2.0]", "'prior_weight' needs 3"),
        ("map_update_angle_deg: -1", "'map_update_angle_deg' must not be negative"),
        ("hit_offset: 1.0", "'hit_offset' must be in"),
        ("no_return_range: -1", "'no_return_range' must not be negative"),
        ("resolutoin: 0.05", "unknown key 'resolutoin'"),
    ],
)
def test_bad_config_is_one_line_naming_the_key(tmp_path, text, match):
    path = tmp_path / "slam.yaml"
    path.write_text(text + "\n")
    with pytest.raises(ConfigError, match=match) as info:
        mut.load_slam_config(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_the_loop_closure_section_is_read_and_checked(tmp_path):
    path = tmp_path / "slam.yaml"
    path.write_text("loop_closure: {enabled: true, min_travel: 20.0}\nno_return_range: 0\n")
    loaded = mut.load_slam_config(path)
    assert loaded.loop_closure.enabled and loaded.loop_closure.min_travel == 20.0
    assert not mut.SlamConfig().loop_closure.enabled  # off unless asked for
    path.write_text("loop_closure: {window_xy: -1}\n")
    with pytest.raises(ConfigError, match="loop_closure: 'window_xy' must be positive"):
        mut.load_slam_config(path)


def test_the_map_square_is_centred_on_the_start_when_that_holds_the_place():
    center, side = mut.map_square([-4.0, -3.0], [4.0, 3.0], [-3.0, -2.0], 30.0)
    assert side == 30.0 and center.tolist() == [-3.0, -2.0]


def test_a_place_the_start_centred_square_misses_gets_a_square_that_holds_it():
    # An 18 x 14 m hall entered at its corner: 30 m centred on the start reached 7 m of 9.
    low, high, start = [-9.1, -7.1], [9.1, 7.1], [-8.0, -6.0]
    center, side = mut.map_square(low, high, start, 30.0)
    assert side == 30.0 and center.tolist() == pytest.approx([0.0, 0.0])
    center, side = mut.map_square(low, high, start, 10.0, margin=0.5)
    assert side == pytest.approx(19.2 + 0.5)  # the larger side, the margins, some slack
    assert all(center - side / 2 <= np.subtract(low, 0.5))
    assert all(center + side / 2 >= np.add(high, 0.5))
