"""drake_sim.systems.estimation.slam_config: the SLAM's defaults, its YAML file, and every bad
value named in one line."""

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
