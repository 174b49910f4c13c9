"""Occupancy maps and map_server's file format (``.pgm`` image + ``.yaml`` description).

``OccupancyMap`` holds a grid in the ROS ``nav_msgs/OccupancyGrid`` convention: ``cells`` (int8,
shape (rows, cols)) is -1 unknown, 0 free, 100 occupied (values in between allowed, as
probabilities in percent); ``resolution`` is m per cell; ``origin`` = (x, y, yaw) (m, m, rad) is
the pose in the world of the lower-left corner of cell [0, 0]. The row index grows with y and
the column index with x (in the origin's frame), so ``cells[0]`` is the bottom row.

``save_map`` writes what nav2's ``map_saver`` writes in trinary mode: a binary PGM (P5, top image
row = highest y) with free 254, occupied 0, unknown 205, and a YAML file with ``image``,
``mode``, ``resolution``, ``origin``, ``negate``, ``occupied_thresh`` and ``free_thresh``.
One deliberate difference: ``free_thresh`` defaults to ROS 1's 0.196, not nav2's 0.25, with
which map_server loads the unknown grey (p = 50/255 = 0.196) as free (slam_toolbox issue #587).
``load_map`` reads a map the way nav2's ``map_server`` does (``negate``, thresholds, modes
``trinary``, ``scale`` and ``raw``; PGM P5 or P2, or any image Pillow reads). In ``scale`` mode
a value between the thresholds is ``rint(100 * ratio)`` of its place between them, as nav2
rounds (``scale_rounding="ros1"``: ROS 1's ``int(99 * ratio)``), and a transparent pixel is
unknown, as both do. Keys map_server does not read (``map_type``, ...) are ignored with one
warning line naming them, as map_server ignores them. Floats are written with the shortest text
that reads back exactly, so save -> load -> save gives identical bytes.

Every problem with a map file is one ``MapFileError`` line naming the file and the problem.
"""

import contextlib
import dataclasses as dc
import json
import logging
import math
import re
from pathlib import Path

import numpy as np

from drake_sim.base.config import parse_yaml, read_text
from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic_many
from drake_sim.base.planar_grid import PlanarGrid

UNKNOWN, FREE, OCCUPIED = -1, 0, 100
PGM_FREE, PGM_OCCUPIED, PGM_UNKNOWN = 254, 0, 205
MODES = ("trinary", "scale", "raw")
# ROS 1's map_saver value. nav2's default, 0.25, makes map_server read the unknown grey 205
# (p = 50/255 = 0.196) as free, so a map saved with it does not load back as it was saved.
FREE_THRESH = 0.196
_REQUIRED = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh")
_KEYS = (*_REQUIRED, "mode")
_PLAIN = re.compile(r"[A-Za-z0-9_./+-]+")
SCALE_ROUNDING = ("nav2", "ros1")
_log = logging.getLogger(__name__)


class MapFileError(ConfigError):
    """A map file (``.yaml`` or its image) is missing, unreadable or malformed."""


@dc.dataclass(eq=False)
class OccupancyMap(PlanarGrid):
    """A 2D occupancy grid, ``nav_msgs/OccupancyGrid`` style (see the module docstring); its
    cells and world points convert with ``PlanarGrid``'s methods (``cell_of``, ``centres``, ...).

    Attributes:
        cells: int8 (rows, cols): -1 unknown, 0 free, 100 occupied, in between allowed.
        resolution: m per cell.
        origin: (x, y, yaw) of the lower-left corner of cell [0, 0] in the world (m, m, rad).
    """

    cells: np.ndarray
    resolution: float
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self):
        cells = np.asarray(self.cells)
        if cells.ndim != 2:
            raise ValueError(f"OccupancyMap cells must be 2D, got shape {cells.shape}")
        if cells.size and (cells.min() < -1 or cells.max() > 100):
            raise ValueError("OccupancyMap cells must be in [-1, 100]")
        self.cells = np.ascontiguousarray(cells, dtype=np.int8)
        if not (math.isfinite(self.resolution) and self.resolution > 0):
            raise ValueError(f"OccupancyMap resolution must be positive, got {self.resolution}")
        origin = tuple(float(v) for v in self.origin)
        if len(origin) != 3 or not all(math.isfinite(v) for v in origin):
            raise ValueError(f"OccupancyMap origin must be 3 finite numbers, got {self.origin}")
        self.resolution = float(self.resolution)
        self.origin = origin

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols)."""
        return self.cells.shape

    @property
    def width_m(self) -> float:
        """Extent along the columns (x of the origin's frame), m."""
        return self.cells.shape[1] * self.resolution

    @property
    def height_m(self) -> float:
        """Extent along the rows (y of the origin's frame), m."""
        return self.cells.shape[0] * self.resolution

    def value_at(self, xy, outside: int = UNKNOWN) -> np.ndarray:
        """Cell values (int8) at world points ``xy`` (..., 2) m; ``outside`` beyond the map."""
        return self.values_at(self.cells, xy, outside)

    def occupied(self, thresh: float = 0.65) -> np.ndarray:
        """Mask of cells whose value is at least ``thresh`` * 100."""
        return self.cells >= round(thresh * 100)

    def free(self, thresh: float = 0.25) -> np.ndarray:
        """Mask of known cells whose value is at most ``thresh`` * 100."""
        return (self.cells >= 0) & (self.cells <= round(thresh * 100))

    def unknown(self) -> np.ndarray:
        """Mask of unknown cells (negative values)."""
        return self.cells < 0


def save_map(
    occupancy_map: OccupancyMap,
    stem: Path | str,
    *,
    occupied_thresh: float = 0.65,
    free_thresh: float = FREE_THRESH,
) -> tuple[Path, Path]:
    """Writes ``stem.pgm`` and ``stem.yaml`` as nav2's map_saver does in trinary mode.

    A cell is occupied (0) when its value is at least round(occupied_thresh * 100), free (254)
    when it is in [0, round(free_thresh * 100)], else unknown (205). Missing folders are made.
    Both files are written atomically, as a pair (``files.write_atomic_many``): an existing map
    is either left whole or replaced whole.

    Returns:
        (pgm path, yaml path).
    """
    _check_thresholds(occupied_thresh, free_thresh, "save_map")
    stem = Path(stem)
    pgm, yml = stem.with_name(stem.name + ".pgm"), stem.with_name(stem.name + ".yaml")
    cells = occupancy_map.cells.astype(np.int16)
    image = np.full(cells.shape, PGM_UNKNOWN, dtype=np.uint8)
    image[(cells >= 0) & (cells <= round(free_thresh * 100))] = PGM_FREE
    image[(cells >= round(occupied_thresh * 100)) & (cells <= 100)] = PGM_OCCUPIED
    rows, cols = cells.shape
    origin = ", ".join(_number(v) for v in occupancy_map.origin)
    name = pgm.name if _PLAIN.fullmatch(pgm.name) else json.dumps(pgm.name)
    text = (
        f"image: {name}\n"
        "mode: trinary\n"
        f"resolution: {_number(occupancy_map.resolution)}\n"
        f"origin: [{origin}]\n"
        "negate: 0\n"
        f"occupied_thresh: {_number(occupied_thresh)}\n"
        f"free_thresh: {_number(free_thresh)}\n"
    )
    image_bytes = b"P5\n%d %d\n255\n" % (cols, rows) + np.flipud(image).tobytes()
    write_atomic_many([(pgm, image_bytes), (yml, text)], "map")
    return pgm, yml


def load_map(yaml_path: Path | str, *, scale_rounding: str = "nav2") -> OccupancyMap:
    """Reads a map_server map (its ``.yaml`` and the image it names).

    Each pixel's occupancy is p = (255 - value) / 255 (value / 255 with ``negate``); in mode
    ``trinary``, p > occupied_thresh is occupied (100), p < free_thresh free (0), else unknown
    (-1); ``scale`` gives the values in between linearly (nav2: ``rint(100 * ratio)``; with
    ``scale_rounding="ros1"``, ROS 1's ``int(99 * ratio)``) and transparent pixels unknown;
    ``raw`` takes the pixel value as the cell value (values above 100 unknown). Colour images
    are averaged over R, G, B. Keys map_server does not read are ignored (one warning line).

    Raises:
        MapFileError: one line naming the file and the problem.
        ValueError: an unknown ``scale_rounding``.
    """
    if scale_rounding not in SCALE_ROUNDING:
        raise ValueError(f"scale_rounding must be one of {SCALE_ROUNDING}, not {scale_rounding!r}")
    yaml_path = Path(yaml_path)
    where = str(yaml_path)
    try:
        tree = parse_yaml(read_text(yaml_path, "map file"), where)
    except MapFileError:
        raise
    except ConfigError as e:
        raise MapFileError(str(e)) from None
    if not isinstance(tree, dict):
        raise MapFileError(f"{where}: expected a mapping of map_server keys")
    ignored = [str(k) for k in tree if k not in _KEYS]
    if ignored:
        _log.warning(
            "%s: ignored keys %s (map_server does not read them)", where, ", ".join(ignored)
        )
    missing = [k for k in _REQUIRED if k not in tree]
    if missing:
        raise MapFileError(f"{where}: missing key '{missing[0]}'")
    resolution = _finite(tree["resolution"], where, "resolution")
    if resolution <= 0:
        raise MapFileError(f"{where}: 'resolution' must be positive, got {resolution}")
    origin = tree["origin"]
    if not isinstance(origin, list) or len(origin) != 3:
        raise MapFileError(f"{where}: 'origin' must be a list [x, y, yaw], got {origin!r}")
    origin = tuple(_finite(v, where, f"origin[{i}]") for i, v in enumerate(origin))
    negate = tree["negate"]
    if negate not in (0, 1) or isinstance(negate, float):
        raise MapFileError(f"{where}: 'negate' must be 0 or 1, got {negate!r}")
    occupied_thresh = _finite(tree["occupied_thresh"], where, "occupied_thresh")
    free_thresh = _finite(tree["free_thresh"], where, "free_thresh")
    _check_thresholds(occupied_thresh, free_thresh, where)
    mode = tree.get("mode", "trinary")
    if mode not in MODES:
        raise MapFileError(f"{where}: 'mode' must be one of {', '.join(MODES)}, got {mode!r}")
    image_name = tree["image"]
    if not isinstance(image_name, str) or not image_name.strip():
        raise MapFileError(f"{where}: 'image' must be a file name, got {image_name!r}")
    image_path = Path(image_name)
    if not image_path.is_absolute():
        image_path = yaml_path.parent / image_path
    pixels = read_image(image_path).astype(np.float64)
    cells = _cells(pixels, bool(negate), occupied_thresh, free_thresh, mode, scale_rounding)
    if mode == "scale":
        cells[~_opaque(image_path, pixels.shape)] = UNKNOWN
    return OccupancyMap(np.flipud(cells), resolution, origin)


def read_image(path: Path | str) -> np.ndarray:
    """Returns a grey image (rows top to bottom, uint8 0..255) from a PGM (P5/P2) or, with
    Pillow, any other image format (colour averaged over R, G, B).

    Raises:
        MapFileError: missing, unreadable, not an image, bad header, wrong maxval, truncated.
    """
    path = Path(path)
    if not path.is_file():
        raise MapFileError(f"{path}: no such map image" + (" (a directory)" * path.is_dir()))
    try:
        data = path.read_bytes()
    except OSError as e:
        raise MapFileError(f"{path}: cannot read map image ({e.strerror})") from None
    if data[:2] in (b"P5", b"P2"):
        return _read_pgm(data, path)
    return _read_other_image(path)


def _read_pgm(data: bytes, path: Path) -> np.ndarray:
    tokens, pos = [], 2
    while len(tokens) < 3:
        while pos < len(data) and (data[pos : pos + 1].isspace() or data[pos] == ord("#")):
            if data[pos] == ord("#"):
                end = data.find(b"\n", pos)
                pos = len(data) if end < 0 else end
            pos += 1
        start = pos
        while pos < len(data) and not data[pos : pos + 1].isspace() and data[pos] != ord("#"):
            pos += 1
        if start == pos:
            raise MapFileError(f"{path}: truncated PGM header")
        tokens.append(data[start:pos])
    try:
        width, height, maxval = (int(t) for t in tokens)
    except ValueError:
        raise MapFileError(f"{path}: malformed PGM header {b' '.join(tokens)!r}") from None
    if width <= 0 or height <= 0:
        raise MapFileError(f"{path}: PGM size must be positive, got {width} x {height}")
    if not 0 < maxval < 256:
        raise MapFileError(f"{path}: PGM maxval must be in 1..255, got {maxval}")
    count = width * height
    if data[:2] == b"P5":
        if pos >= len(data) or not data[pos : pos + 1].isspace():
            raise MapFileError(f"{path}: truncated PGM header")
        body = np.frombuffer(data, dtype=np.uint8, count=-1, offset=pos + 1)
        if body.size < count:
            raise MapFileError(f"{path}: truncated PGM data ({body.size} of {count} bytes)")
        values = body[:count].astype(np.int64)
    else:
        text = re.sub(rb"#[^\n]*", b" ", data[pos:])
        try:
            values = np.array([int(t) for t in text.split()[:count]], dtype=np.int64)
        except ValueError:
            raise MapFileError(f"{path}: malformed P2 PGM data") from None
        if values.size < count:
            raise MapFileError(f"{path}: truncated PGM data ({values.size} of {count} values)")
    if values.max(initial=0) > maxval:
        raise MapFileError(f"{path}: PGM value {values.max()} above maxval {maxval}")
    if maxval != 255:
        values = np.rint(values * 255.0 / maxval).astype(np.int64)
    return values.reshape(height, width).astype(np.uint8)


def _read_other_image(path: Path) -> np.ndarray:
    try:
        from PIL import Image, UnidentifiedImageError
    except ImportError:  # pragma: no cover (Pillow is a dependency here)
        raise MapFileError(f"{path}: not a PGM image (install Pillow for others)") from None
    try:
        with Image.open(path) as image:
            image.load()
            if image.mode in ("L", "P", "1", "LA", "RGB", "RGBA", "PA"):
                rgb = np.asarray(image.convert("RGB"), dtype=np.float64)
                if image.mode in ("L", "LA", "1"):
                    return rgb[..., 0].astype(np.uint8)
                return np.rint(rgb.mean(axis=-1)).astype(np.uint8)
            raise MapFileError(f"{path}: unsupported image mode {image.mode}")
    except UnidentifiedImageError:
        raise MapFileError(f"{path}: not an image (expected PGM P5/P2 or PNG)") from None
    except OSError as e:
        raise MapFileError(f"{path}: cannot read map image ({e})") from None


def _cells(pixels, negate, occupied_thresh, free_thresh, mode, rounding="nav2") -> np.ndarray:
    if mode == "raw":
        raw = pixels.astype(np.int16)
        return np.where(raw > 100, UNKNOWN, raw).astype(np.int8)
    p = pixels / 255.0 if negate else (255.0 - pixels) / 255.0
    cells = np.full(p.shape, UNKNOWN, dtype=np.int8)
    if mode == "scale":
        ratio = (p - free_thresh) / (occupied_thresh - free_thresh)
        scaled = np.rint(100.0 * ratio) if rounding == "nav2" else np.trunc(99.0 * ratio)
        between = (p >= free_thresh) & (p <= occupied_thresh)
        cells[between] = scaled[between]
    cells[p > occupied_thresh] = OCCUPIED
    cells[p < free_thresh] = FREE
    return cells


def _opaque(path: Path, shape) -> np.ndarray:
    """Which pixels of a map image are opaque (all of a PGM's; an image with an alpha channel:
    those with alpha 255, which map_server's scale mode requires of a known cell)."""
    with open(path, "rb") as f:
        if f.read(2) in (b"P5", b"P2"):
            return np.ones(shape, dtype=bool)
    from PIL import Image

    with Image.open(path) as image:
        if "A" not in image.getbands() and "transparency" not in image.info:
            return np.ones(shape, dtype=bool)
        return np.asarray(image.convert("RGBA"))[..., 3] == 255


def _finite(value, where: str, key: str) -> float:
    if isinstance(value, str):
        with contextlib.suppress(ValueError):
            value = float(value)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise MapFileError(f"{where}: '{key}' must be a number, got {value!r}")
    if not math.isfinite(value):
        raise MapFileError(f"{where}: '{key}' must be finite, got {value!r}")
    return float(value)


def _check_thresholds(occupied_thresh: float, free_thresh: float, where: str) -> None:
    for key, value in (("occupied_thresh", occupied_thresh), ("free_thresh", free_thresh)):
        if not 0.0 <= value <= 1.0:
            raise MapFileError(f"{where}: '{key}' must be in [0, 1], got {value}")
    if free_thresh >= occupied_thresh:
        raise MapFileError(
            f"{where}: 'free_thresh' ({free_thresh}) must be below 'occupied_thresh' "
            f"({occupied_thresh})"
        )


def _number(value: float) -> str:
    """The shortest text that PyYAML (YAML 1.1) and yaml-cpp read back as exactly ``value``."""
    text = repr(float(value))
    mantissa, e, exponent = text.partition("e")
    if e:
        if "." not in mantissa:
            mantissa += ".0"
        sign = "" if exponent[0] in "+-" else "+"
        text = f"{mantissa}e{sign}{exponent}"
    return text
