"""An arena as a Gazebo-style SDF world for Drake: a ground slab, the walls and the obstacles.

``arena_sdf`` writes one static SDFormat model (every link welded to the world) from the
arena's footprints (``drake_sim.worlds.arena.arena_footprints``): a link ``ground`` whose box
top is the floor at z = 0, and one link per wall and obstacle, named after its footprint, with
a box (walls, boxes) or cylinder standing on the floor. Each has collision and visual geometry
of the same shape, so the scene that a lidar sees, the contact geometry and the ground-truth
grid (``arena_grid``) all come from the same numbers. Visuals: walls grey, boxes brown,
cylinders blue, the floor a light grey.

``add_arena`` writes that text to ``cache_dir()/arenas/<hash>.sdf`` (the hash covers the text,
so a changed arena gets a new file) and parses it into a plant. An arena of more than
``MAX_LINKS`` walls and obstacles (a map's world, ``drake_sim.worlds.map_world``: nav2's depot
has 1,327 boxes) keeps only its ``ground`` link there: its walls and obstacles are registered on
the world body itself, with the same names, shapes, colours and friction. Drake treats geometry
on the world body as anchored, while every welded link is a body the plant poses at each step:
measured, 2 s of the TurtleBot3 in the depot took 4.7 s with a link per box and 0.15 s anchored.
"""

import dataclasses as dc
import hashlib
import os
from xml.sax.saxutils import quoteattr

import numpy as np
from pydrake.geometry import Box, Cylinder
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex

from drake_sim.base.resources import cache_dir, make_parser
from drake_sim.worlds.arena import Arena, arena_bounds, arena_footprints
from drake_sim.worlds.footprints import Footprint

GROUND_THICKNESS = 0.1
"""m: the ground slab's thickness below z = 0."""

GROUND_MARGIN = 1.0
"""m: how far the ground extends past the outer walls on every side."""

GROUND_FRICTION = (1.0, 0.8)
"""The floor's static and dynamic Coulomb friction (rubber wheels on a smooth floor)."""

OBSTACLE_FRICTION = (0.5, 0.4)
"""Static and dynamic Coulomb friction of walls and obstacles."""

COLOURS = {
    "ground": (0.3, 0.33, 0.37, 1.0),  # dark, so the map drawn on it stands out
    "wall": (0.7, 0.7, 0.68, 1.0),
    "box": (0.65, 0.42, 0.2, 1.0),
    "cylinder": (0.2, 0.45, 0.75, 1.0),
}
"""RGBA of each kind of visual."""

MAX_LINKS = 100
"""Walls and obstacles an arena's SDF model holds as links; more are anchored (see above)."""


def _num(value: float) -> str:
    return repr(float(value))


def _nums(*values: float) -> str:
    return " ".join(_num(v) for v in values)


def _shape(footprint: Footprint) -> str:
    if footprint.is_circle:
        return (
            f"<cylinder><radius>{_num(footprint.radius)}</radius>"
            f"<length>{_num(footprint.height)}</length></cylinder>"
        )
    hx, hy = footprint.half_size
    return f"<box><size>{_nums(2 * hx, 2 * hy, footprint.height)}</size></box>"


def _link(name: str, pose: str, shape: str, colour, friction) -> str:
    mu_static, mu_dynamic = friction
    return f"""    <link name={quoteattr(name)}>
      <collision name="collision">
        <pose>{pose}</pose>
        <geometry>{shape}</geometry>
        <drake:proximity_properties>
          <drake:mu_static>{_num(mu_static)}</drake:mu_static>
          <drake:mu_dynamic>{_num(mu_dynamic)}</drake:mu_dynamic>
        </drake:proximity_properties>
      </collision>
      <visual name="visual">
        <pose>{pose}</pose>
        <geometry>{shape}</geometry>
        <material><diffuse>{_nums(*colour)}</diffuse></material>
      </visual>
    </link>
"""


def arena_sdf(arena: Arena, *, name: str = "arena") -> str:
    """Returns the SDFormat text of ``arena`` as one static model called ``name``.

    Frames: the model frame is the world frame W; every geometry stands on z = 0.
    """
    lo, hi = arena_bounds(arena, walls=True)
    sx, sy = hi - lo + 2 * GROUND_MARGIN
    ground = f"<box><size>{_nums(sx, sy, GROUND_THICKNESS)}</size></box>"
    links = [
        _link(
            "ground",
            _nums(0, 0, -GROUND_THICKNESS / 2, 0, 0, 0),
            ground,
            COLOURS["ground"],
            GROUND_FRICTION,
        )
    ]
    for footprint in arena_footprints(arena):
        x, y = footprint.centre
        pose = _nums(x, y, footprint.height / 2, 0, 0, footprint.yaw)
        links.append(
            _link(
                footprint.name,
                pose,
                _shape(footprint),
                COLOURS[footprint.kind],
                OBSTACLE_FRICTION,
            )
        )
    return (
        '<?xml version="1.0"?>\n'
        '<sdf version="1.9" xmlns:drake="http://drake.mit.edu">\n'
        f"  <model name={quoteattr(name)}>\n"
        "    <static>true</static>\n" + "".join(links) + "  </model>\n</sdf>\n"
    )


def arena_sdf_file(arena: Arena, *, name: str = "arena"):
    """Returns the path of ``arena``'s SDF file in ``cache_dir()/arenas/``, writing it unless a
    file with the same text is already there."""
    text = arena_sdf(arena, name=name)
    folder = cache_dir() / "arenas"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{hashlib.sha256(text.encode()).hexdigest()[:16]}.sdf"
    if not path.is_file():
        tmp = path.with_suffix(f".tmp{os.getpid()}")
        tmp.write_text(text)
        tmp.replace(path)
    return path


def add_arena(plant: MultibodyPlant, arena: Arena, *, name: str = "arena") -> ModelInstanceIndex:
    """Adds ``arena`` (ground, walls, obstacles; all welded to the world, or anchored beyond
    ``MAX_LINKS``) to ``plant`` before ``Finalize`` and returns its model instance, called
    ``name``."""
    footprints = arena_footprints(arena)
    if len(footprints) <= MAX_LINKS:
        (instance,) = make_parser(plant).AddModels(str(arena_sdf_file(arena, name=name)))
        return instance
    ground_only = dc.replace(arena, obstacles=[])
    (instance,) = make_parser(plant).AddModels(str(arena_sdf_file(ground_only, name=name)))
    outer = {f.name for f in arena_footprints(ground_only)}
    world = plant.world_body()
    mu_static, mu_dynamic = OBSTACLE_FRICTION
    for footprint in footprints:
        if footprint.name in outer:
            continue  # in the SDF model already
        x, y = footprint.centre
        X = RigidTransform(RollPitchYaw(0.0, 0.0, footprint.yaw), [x, y, footprint.height / 2])
        if footprint.is_circle:
            shape = Cylinder(footprint.radius, footprint.height)
        else:
            hx, hy = footprint.half_size
            shape = Box(2 * hx, 2 * hy, footprint.height)
        plant.RegisterCollisionGeometry(
            world, X, shape, footprint.name, CoulombFriction(mu_static, mu_dynamic)
        )
        plant.RegisterVisualGeometry(
            world, X, shape, footprint.name, np.asarray(COLOURS[footprint.kind])
        )
    return instance
