"""A course's floor: the image of its line, a textured floor mesh, and the floor in a plant.

``draw_floor`` paints the course as a camera should see it: a black floor and a white line of
``line_width`` along the centreline, antialiased (each pixel's grey level is the fraction of it
the line covers). The pixels are ``line_width / PIXELS_ACROSS_LINE`` metres wide, so a 3 cm line
is 8 pixels across, unless the floor is so large that the image would pass ``MAX_IMAGE_SIZE``.

``floor_files`` writes the image with a one-quad OBJ/MTL floor mesh (``drake_sim.base.obj_mesh``)
into ``cache_dir()/courses/<hash>/``, where the hash covers every value of the course and this
module's ``FLOOR_VERSION``: the same course reuses its files, a changed one gets new ones.
``add_course_floor`` registers the mesh as the plant's visible floor and a half-space as its
ground.

Frames: the floor lies in the world frame W's z = 0 plane; its image's column 0 is the floor's
lowest x and its row 0 the highest y (the picture seen from above with x to the right).
"""

import dataclasses as dc
import hashlib
import json
import logging
import math
import os
import shutil
from pathlib import Path

import numpy as np
from PIL import Image
from pydrake.geometry import (
    AddContactMaterial,
    GeometryInstance,
    HalfSpace,
    IllustrationProperties,
    Mesh,
    PerceptionProperties,
    ProximityProperties,
)
from pydrake.math import RigidTransform
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant

from drake_sim.base.errors import ConfigError
from drake_sim.base.obj_mesh import ObjWriter, mtl
from drake_sim.base.resources import cache_dir
from drake_sim.worlds.course import Course, centreline, nearest_on_chords

FLOOR_VERSION = "1"
"""Changes whenever this module draws a floor differently, so cached floors are regenerated."""

PIXELS_ACROSS_LINE = 8
"""How many image pixels the line's width spans (unless the floor is too large)."""

MIN_PIXELS_ACROSS_LINE = 3
"""A course whose line would be narrower than this in its image is rejected."""

MAX_IMAGE_SIZE = 4096
"""Pixels, the longest side of a floor image."""

FLOOR_GREY = 0.06
"""The black floor's reflectance, 0 to 1 (a little above zero, like black paint)."""

LINE_GREY = 0.95
"""The white line's reflectance, 0 to 1."""

FLOOR_NAME = "course_floor"
"""The name of the floor's visual geometry (and of its ground half-space)."""

_GENERATOR = "drake_sim.worlds.course_floor"


@dc.dataclass(frozen=True)
class FloorLayout:
    """Where the floor image lies on the floor: its lower (x, y) corner and pixel size."""

    x0: float  # m, W's x of the image's left edge.
    y0: float  # m, W's y of the image's bottom edge.
    pixel: float  # m, the side of one square pixel.
    columns: int
    rows: int

    @property
    def size(self) -> tuple[float, float]:
        """The floor's extent along x and y, m."""
        return self.columns * self.pixel, self.rows * self.pixel

    def pixel_centres(self, rows: slice, columns: slice) -> tuple[np.ndarray, np.ndarray]:
        """Returns the W x and y (m) of the centres of the pixels in ``rows`` x ``columns``."""
        r = np.arange(self.rows)[rows]
        c = np.arange(self.columns)[columns]
        x = self.x0 + (c + 0.5) * self.pixel
        y = self.y0 + (self.rows - r - 0.5) * self.pixel
        return x[None, :], y[:, None]


@dc.dataclass(frozen=True)
class FloorFiles:
    """The generated floor: its folder and the mesh, material and texture files in it."""

    folder: Path
    obj: Path
    mtl: Path
    png: Path


def floor_layout(course: Course, where: str = "course") -> FloorLayout:
    """Returns the layout of ``course``'s floor: the line's bounding box plus ``floor_margin`` on
    every side (plus half the line's width), in whole pixels.

    Raises:
        ConfigError: the floor is too large to draw the line at least ``MIN_PIXELS_ACROSS_LINE``
            pixels wide in a ``MAX_IMAGE_SIZE`` image.
    """
    lo, hi = centreline(course).bounds()
    pad = course.floor_margin + 0.5 * course.line_width
    lo, hi = lo - pad, hi + pad
    extent = float(np.max(hi - lo))
    pixel = max(course.line_width / PIXELS_ACROSS_LINE, extent / MAX_IMAGE_SIZE)
    if course.line_width / pixel < MIN_PIXELS_ACROSS_LINE - 1e-9:
        raise ConfigError(
            f"{where}: 'segments' span {extent:.1f} m, too large a floor for a "
            f"{course.line_width} m 'line_width' (at most "
            f"{MAX_IMAGE_SIZE * course.line_width / MIN_PIXELS_ACROSS_LINE:.1f} m)"
        )
    columns, rows = (int(math.ceil((hi[k] - lo[k]) / pixel - 1e-9)) for k in range(2))
    return FloorLayout(float(lo[0]), float(lo[1]), pixel, columns, rows)


def draw_floor(course: Course, layout: FloorLayout | None = None) -> np.ndarray:
    """Returns the floor image, a (rows, columns) float array of reflectance (0 to 1).

    A pixel's value is FLOOR_GREY plus (LINE_GREY - FLOOR_GREY) times the fraction of the pixel
    the line covers, estimated from the distance d of its centre to the centreline:
    ``clip(0.5 + (line_width / 2 - d) / pixel, 0, 1)``.
    """
    layout = layout or floor_layout(course)
    line = centreline(course)
    half, px = 0.5 * course.line_width, layout.pixel
    distance = np.full((layout.rows, layout.columns), np.inf)
    chunk = 16  # chords per window: a window of pixels around a short run of the line
    reach = half + 2 * px
    for i in range(0, len(line.p_WP) - 1, chunk):
        a = line.p_WP[i : min(i + chunk, len(line.p_WP) - 1)]
        b = line.p_WP[i + 1 : i + 1 + len(a)]
        lo = np.minimum(a.min(axis=0), b.min(axis=0)) - reach
        hi = np.maximum(a.max(axis=0), b.max(axis=0)) + reach
        c0, c1 = (
            np.clip((v - layout.x0) / px, 0, layout.columns).astype(int) for v in (lo[0], hi[0])
        )
        r0, r1 = (
            np.clip(layout.rows - (v - layout.y0) / px, 0, layout.rows).astype(int)
            for v in (hi[1], lo[1])
        )
        if c1 <= c0 or r1 <= r0:
            continue
        rows, cols = slice(r0, r1 + 1), slice(c0, c1 + 1)
        x, y = np.broadcast_arrays(*layout.pixel_centres(rows, cols))
        _, _, d2 = nearest_on_chords(np.column_stack([x.ravel(), y.ravel()]), a, b)
        window = distance[rows, cols]
        distance[rows, cols] = np.minimum(window, np.sqrt(d2).reshape(window.shape))
    coverage = np.clip(0.5 + (half - distance) / px, 0.0, 1.0)
    return FLOOR_GREY + (LINE_GREY - FLOOR_GREY) * coverage


def course_hash(course: Course) -> str:
    """Returns a short hash of every value of ``course`` and of ``FLOOR_VERSION``."""
    text = json.dumps(dc.asdict(course), sort_keys=True) + f"\nfloor {FLOOR_VERSION}"
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def floor_files(course: Course) -> FloorFiles:
    """Returns ``course``'s floor files, generating them into ``cache_dir()/courses/<hash>/``
    unless they are already there. The floor mesh is one quad at z = 0 covering the layout."""
    folder = cache_dir() / "courses" / course_hash(course)
    files = FloorFiles(folder, folder / "floor.obj", folder / "floor.mtl", folder / "floor.png")
    if all(path.is_file() for path in (files.obj, files.mtl, files.png)):
        return files
    layout = floor_layout(course)
    grey = np.round(255 * draw_floor(course, layout)).astype(np.uint8)
    tmp = folder.with_name(f"{folder.name}.tmp{os.getpid()}")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    Image.fromarray(np.repeat(grey[..., None], 3, axis=2)).save(tmp / files.png.name)
    (tmp / files.mtl.name).write_bytes(
        mtl({"floor": ((1.0, 1.0, 1.0), files.png.name)}, generator=_GENERATOR)
    )
    (tmp / files.obj.name).write_bytes(_floor_obj(layout, files.mtl.name))
    try:
        tmp.replace(folder)
    except OSError:  # another process wrote the same floor first; its files are the same
        shutil.rmtree(tmp, ignore_errors=True)
    return files


def _floor_obj(layout: FloorLayout, mtllib: str) -> bytes:
    """Returns the floor's OBJ text: one textured quad at z = 0, normal up."""
    sx, sy = layout.size
    corners = np.array([(0.0, 0.0), (sx, 0.0), (sx, sy), (0.0, sy)])
    points = np.column_stack([corners + [layout.x0, layout.y0], np.zeros(4)])
    writer = ObjWriter()
    writer.polygon(
        points, normal=np.array([0.0, 0.0, 1.0]), uvs=corners / [sx, sy], material="floor"
    )
    return writer.text("Line-following course floor", mtllib, generator=_GENERATOR)


def add_course_floor(
    plant: MultibodyPlant,
    course: Course,
    *,
    mu_static: float = 1.0,
    mu_dynamic: float = 0.9,
) -> FloorFiles:
    """Adds ``course``'s floor to ``plant`` (before ``Finalize``): the textured mesh as a visual
    (seen by Meshcat and by cameras) and a half-space at z = 0 as the ground it collides with.

    Args:
        plant: the MultibodyPlant, registered with a SceneGraph.
        course: the course (checked).
        mu_static: the ground's static Coulomb friction (rubber tyres on a painted floor).
        mu_dynamic: the ground's dynamic Coulomb friction, at most ``mu_static``.

    Returns:
        The floor's files.
    """
    files = floor_files(course)
    world = plant.world_body()
    visual = GeometryInstance(RigidTransform(), Mesh(str(files.obj)), FLOOR_NAME)
    # Empty properties: the renderers take the colours from the mesh's own material.
    visual.set_illustration_properties(IllustrationProperties())
    visual.set_perception_properties(PerceptionProperties())
    plant.RegisterVisualGeometry(world, visual)
    props = ProximityProperties()
    AddContactMaterial(friction=CoulombFriction(mu_static, mu_dynamic), properties=props)
    plant.RegisterCollisionGeometry(world, RigidTransform(), HalfSpace(), FLOOR_NAME, props)
    drake_logger = logging.getLogger("drake")
    if _not_about_deformables not in drake_logger.filters:
        drake_logger.addFilter(_not_about_deformables)
    return files


def _not_about_deformables(record: logging.LogRecord) -> bool:
    """Drops Drake's warning that deformable bodies cannot touch a rigid half-space (there are
    none here, and it would print for every context)."""
    return "half spaces are not currently supported for deformable" not in record.getMessage()
