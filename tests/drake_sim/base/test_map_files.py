"""drake_sim.base.map_files: map_server's format, byte-exact round trips, one-line errors."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import drake_sim.base.map_files as mut
from drake_sim.base.errors import ConfigError

ROUND_TRIP = settings(
    max_examples=40,
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)


def small_map() -> mut.OccupancyMap:
    cells = np.full((3, 4), -1, dtype=np.int8)
    cells[0] = 0  # bottom row free
    cells[1, 2] = 100
    cells[2, 0] = 50  # between the thresholds: unknown in a trinary file
    cells[2, 1] = 70  # above occupied_thresh: occupied
    cells[2, 2] = 10  # below free_thresh: free
    return mut.OccupancyMap(cells, 0.05, (-1.5, 2.25, 0.0))


def write(path, text):
    path.write_text(text)
    return path


def test_saved_files_are_what_map_saver_writes(tmp_path):
    pgm, yml = mut.save_map(small_map(), tmp_path / "sub" / "room")
    assert (pgm.name, yml.name) == ("room.pgm", "room.yaml")
    # Top image row first = highest y = cells[2]: unknown, occupied, free, unknown.
    assert pgm.read_bytes() == (
        b"P5\n4 3\n255\n" + bytes([205, 0, 254, 205]) + bytes([205, 205, 0, 205]) + bytes([254] * 4)
    )
    assert yml.read_text() == (
        "image: room.pgm\nmode: trinary\nresolution: 0.05\norigin: [-1.5, 2.25, 0.0]\n"
        "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )


def test_load_follows_map_server(tmp_path):
    mut.save_map(small_map(), tmp_path / "room")
    dut = mut.load_map(tmp_path / "room.yaml")
    assert dut.resolution == 0.05 and dut.origin == (-1.5, 2.25, 0.0)
    expected = [[0, 0, 0, 0], [-1, -1, 100, -1], [-1, 100, 0, -1]]
    np.testing.assert_array_equal(dut.cells, expected)
    assert dut.cells.dtype == np.int8


def test_nav2_default_free_thresh_reads_unknown_grey_as_free(tmp_path):
    # The reason save_map defaults to 0.196: map_server's own rule with nav2's 0.25.
    mut.save_map(small_map(), tmp_path / "m", free_thresh=0.25)
    assert not mut.load_map(tmp_path / "m.yaml").unknown().any()


def test_negate_scale_raw_and_p2(tmp_path):
    write(tmp_path / "g.pgm", "P2\n# a comment\n3 1\n# another\n255\n0 128 255\n")
    base = "image: g.pgm\nresolution: 0.1\norigin: [0, 0, 0]\noccupied_thresh: 0.65\n"
    base += "free_thresh: 0.196\n"
    plain = mut.load_map(write(tmp_path / "a.yaml", base + "negate: 0\n"))
    np.testing.assert_array_equal(plain.cells, [[100, -1, 0]])
    negated = mut.load_map(write(tmp_path / "b.yaml", base + "negate: 1\n"))
    np.testing.assert_array_equal(negated.cells, [[0, -1, 100]])
    scale = mut.load_map(write(tmp_path / "c.yaml", base + "negate: 0\nmode: scale\n"))
    assert scale.cells[0, 0] == 100 and scale.cells[0, 2] == 0 and 1 <= scale.cells[0, 1] <= 99
    raw = mut.load_map(write(tmp_path / "d.yaml", base + "negate: 0\nmode: raw\n"))
    np.testing.assert_array_equal(raw.cells, [[0, -1, -1]])


def test_png_images_load_through_pillow(tmp_path):
    from PIL import Image

    Image.fromarray(np.array([[0, 254], [205, 254]], dtype=np.uint8)).save(tmp_path / "m.png")
    text = "image: m.png\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: 0\n"
    text += "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    dut = mut.load_map(write(tmp_path / "m.yaml", text))
    np.testing.assert_array_equal(dut.cells, [[-1, 0], [100, 0]])


@ROUND_TRIP
@given(
    cells=hnp.arrays(
        np.int8,
        hnp.array_shapes(min_dims=2, max_dims=2, min_side=1, max_side=12),
        elements=st.integers(-1, 100),
    ),
    resolution=st.floats(1e-4, 10.0),
    origin=st.tuples(*[st.floats(-1e4, 1e4, allow_subnormal=False)] * 3),
)
def test_save_load_save_is_byte_exact(tmp_path, cells, resolution, origin):
    first = mut.save_map(mut.OccupancyMap(cells, resolution, origin), tmp_path / "a")
    loaded = mut.load_map(first[1])
    assert loaded.resolution == resolution and loaded.origin == origin
    second = mut.save_map(loaded, tmp_path / "b")
    assert first[0].read_bytes() == second[0].read_bytes()
    assert first[1].read_text().replace("a.pgm", "b.pgm") == second[1].read_text()


def test_numbers_with_exponents_read_back_exactly(tmp_path):
    dut = mut.OccupancyMap(np.zeros((1, 1)), 1e-05, (1e20, -3e-7, 0.0))
    mut.save_map(dut, tmp_path / "e")
    assert "1.0e-05" in (tmp_path / "e.yaml").read_text()
    assert mut.load_map(tmp_path / "e.yaml").origin == (1e20, -3e-7, 0.0)


def test_geometry_helpers():
    dut = mut.OccupancyMap(np.zeros((4, 6)), 0.5, (1.0, -1.0, 0.0))
    assert dut.shape == (4, 6) and dut.width_m == 3.0 and dut.height_m == 2.0
    rows, cols = dut.cell_of(np.array([[1.1, -0.9], [3.9, 0.9], [0.9, 0.0]]))
    np.testing.assert_array_equal(rows, [0, 3, 2])
    np.testing.assert_array_equal(cols, [0, 5, -1])
    np.testing.assert_array_equal(dut.inside(rows, cols), [True, True, False])
    xs, ys = dut.centres()
    assert xs[0, 0] == 1.25 and ys[0, 0] == -0.75 and xs[3, 5] == 3.75 and ys[3, 5] == 0.75
    np.testing.assert_array_equal(dut.value_at([[1.1, -0.9], [0.0, 0.0]]), [0, -1])


def test_rotated_origin_maps_centres_back_to_their_cells():
    dut = mut.OccupancyMap(np.zeros((5, 7)), 0.2, (0.3, -0.4, math.radians(30)))
    xs, ys = dut.centres()
    rows, cols = dut.cell_of(np.stack([xs, ys], -1))
    np.testing.assert_array_equal(rows, np.indices(dut.shape)[0])
    np.testing.assert_array_equal(cols, np.indices(dut.shape)[1])
    assert math.isclose(xs[0, 1] - xs[0, 0], 0.2 * math.cos(math.radians(30)))


def test_masks():
    dut = mut.OccupancyMap(np.array([[-1, 0, 20, 50, 65, 100]]), 1.0)
    np.testing.assert_array_equal(dut.unknown(), [[1, 0, 0, 0, 0, 0]])
    np.testing.assert_array_equal(dut.free(), [[0, 1, 1, 0, 0, 0]])
    np.testing.assert_array_equal(dut.occupied(), [[0, 0, 0, 0, 1, 1]])


@pytest.mark.parametrize(
    "cells, resolution, origin",
    [
        (np.zeros(3), 1.0, (0, 0, 0)),
        (np.zeros((2, 2)), 0.0, (0, 0, 0)),
        (np.full((2, 2), 101), 1.0, (0, 0, 0)),
        (np.zeros((2, 2)), 1.0, (0, math.nan, 0)),
    ],
)
def test_bad_maps_are_rejected(cells, resolution, origin):
    with pytest.raises(ValueError):
        mut.OccupancyMap(cells, resolution, origin)


GOOD_YAML = (
    "image: m.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
    "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
)


@pytest.mark.parametrize(
    "yaml_text, match",
    [
        (
            GOOD_YAML.replace("resolution: 0.05", "resolution: -0.05"),
            "'resolution' must be positive",
        ),
        (GOOD_YAML.replace("resolution: 0.05", "resolution: .nan"), "'resolution' must be finite"),
        (GOOD_YAML.replace("resolution: 0.05\n", ""), "missing key 'resolution'"),
        (GOOD_YAML.replace("[0.0, 0.0, 0.0]", "[0.0, 0.0]"), "'origin' must be a list"),
        (GOOD_YAML.replace("[0.0, 0.0, 0.0]", "[0.0, x, 0.0]"), r"'origin\[1\]' must be a number"),
        (GOOD_YAML.replace("negate: 0", "negate: 2"), "'negate' must be 0 or 1"),
        (GOOD_YAML.replace("0.65", "1.5"), "'occupied_thresh' must be in"),
        (GOOD_YAML.replace("0.196", "0.7"), "'free_thresh' .* must be below"),
        (GOOD_YAML + "mode: fuzzy\n", "'mode' must be one of"),
        (GOOD_YAML.replace("m.pgm", "gone.pgm"), "gone.pgm: no such map image"),
        (GOOD_YAML.replace("image: m.pgm", "image: 3"), "'image' must be a file name"),
        ("- a list", "expected a mapping"),
        ("image: [", "malformed YAML"),
    ],
)
def test_bad_yaml_is_one_line_naming_file_and_key(tmp_path, yaml_text, match):
    (tmp_path / "m.pgm").write_bytes(b"P5\n1 1\n255\n\xfe")
    path = write(tmp_path / "m.yaml", yaml_text)
    with pytest.raises(mut.MapFileError, match=match) as info:
        mut.load_map(path)
    assert "\n" not in str(info.value) and isinstance(info.value, ConfigError)


@pytest.mark.parametrize(
    "image, match",
    [
        (b"P5\n4 3\n255\n" + bytes(5), "truncated PGM data"),
        (b"P5\n4 3\n", "truncated PGM header"),
        (b"P5\n4 3\n65535\n" + bytes(24), "maxval must be in 1..255"),
        (b"P5\n4 x\n255\n" + bytes(12), "malformed PGM header"),
        (b"P5\n0 3\n255\n", "size must be positive"),
        (b"P2\n2 1\n100\n0 200\n", "above maxval"),
        (b"P2\n2 1\n255\n0\n", "truncated PGM data"),
        (b"hello, not an image", "not an image"),
    ],
)
def test_bad_images_are_one_line(tmp_path, image, match):
    (tmp_path / "m.pgm").write_bytes(image)
    path = write(tmp_path / "m.yaml", GOOD_YAML)
    with pytest.raises(mut.MapFileError, match=match) as info:
        mut.load_map(path)
    assert "\n" not in str(info.value)


def test_missing_and_directory_yaml(tmp_path):
    with pytest.raises(mut.MapFileError, match="no such map file"):
        mut.load_map(tmp_path / "nothing.yaml")
    with pytest.raises(mut.MapFileError, match="is a directory"):
        mut.load_map(tmp_path)


def test_pgm_with_other_maxval_is_scaled(tmp_path):
    (tmp_path / "m.pgm").write_bytes(b"P5 2 1 # comment\n15\n\x00\x0f")
    dut = mut.load_map(write(tmp_path / "m.yaml", GOOD_YAML))
    np.testing.assert_array_equal(dut.cells, [[100, 0]])


def test_keys_map_server_does_not_read_are_ignored_with_one_warning(tmp_path, caplog):
    (tmp_path / "m.pgm").write_bytes(b"P5\n1 1\n255\n\xfe")
    path = write(tmp_path / "m.yaml", GOOD_YAML + "map_type: occupancy\nresolutoin: 0.1\n")
    with caplog.at_level("WARNING"):
        dut = mut.load_map(path)
    assert dut.cells.tolist() == [[mut.FREE]]
    (record,) = caplog.records
    assert record.getMessage() == (
        f"{path}: ignored keys map_type, resolutoin (map_server does not read them)"
    )


def test_scale_mode_rounds_like_nav2_or_ros1(tmp_path):
    """Thresholds 0.01 and 0.99, as nav2's speed mask: grey 128 is p = 127/255, ratio 0.498:
    nav2 gives rint(49.8) = 50, ROS 1 int(49.3) = 49; grey 205 (ratio 0.190): 19 and 18."""
    (tmp_path / "m.pgm").write_bytes(b"P5\n4 1\n255\n" + bytes([128, 205, 254, 0]))
    text = GOOD_YAML.replace("occupied_thresh: 0.65", "occupied_thresh: 0.99")
    text = text.replace("free_thresh: 0.196", "free_thresh: 0.01") + "mode: scale\n"
    path = write(tmp_path / "m.yaml", text)
    assert "free_thresh: 0.01" in path.read_text()
    assert mut.load_map(path).cells.tolist() == [[50, 19, 0, 100]]
    assert mut.load_map(path, scale_rounding="ros1").cells.tolist() == [[49, 18, 0, 100]]
    with pytest.raises(ValueError, match="scale_rounding"):
        mut.load_map(path, scale_rounding="ros3")


def test_scale_mode_reads_transparent_pixels_as_unknown(tmp_path):
    from PIL import Image

    rgba = np.array([[[0, 0, 0, 255], [0, 0, 0, 0], [254, 254, 254, 128]]], dtype=np.uint8)
    Image.fromarray(rgba, "RGBA").save(tmp_path / "m.png")
    text = GOOD_YAML.replace("m.pgm", "m.png")
    scale = mut.load_map(write(tmp_path / "s.yaml", text + "mode: scale\n"))
    assert scale.cells.tolist() == [[mut.OCCUPIED, mut.UNKNOWN, mut.UNKNOWN]]
    trinary = mut.load_map(write(tmp_path / "t.yaml", text))  # alpha ignored, as map_server does
    assert trinary.cells.tolist() == [[mut.OCCUPIED, mut.OCCUPIED, mut.FREE]]
