"""Random pick-and-place scenes (``SceneFile``) for tests and benchmarks."""

import dataclasses as dc

import numpy as np

from planning.io.scene_files import BoxSpec, PlaceSpec, SceneFile


def random_scene(rng: np.random.Generator, base: SceneFile) -> SceneFile:
    """A scene like ``base`` (its table) with the object, the place target and the wall drawn at
    random: the object 3-6 cm wide (the hand holds up to 7.5 cm) and 5-10 cm tall, turned by up
    to 45 degrees, in front of the robot on one side of a wall 10-30 cm long and 10-25 cm tall,
    the place target on the other side."""
    side = rng.choice([-1.0, 1.0])
    x_object, x_place = rng.uniform(0.4, 0.62, size=2)
    width, depth = rng.uniform(0.03, 0.06, size=2)
    height = rng.uniform(0.05, 0.10)
    wall = [rng.uniform(0.10, 0.30), rng.uniform(0.02, 0.06), rng.uniform(0.10, 0.25)]
    return dc.replace(
        base,
        object=BoxSpec(
            size=[width, depth, height],
            position=[x_object, side * rng.uniform(0.16, 0.32), 0.5 * height],
            yaw=rng.uniform(-np.pi / 4, np.pi / 4),
            mass=rng.uniform(0.05, 0.3),
        ),
        obstacle=BoxSpec(size=wall, position=[0.5 * (x_object + x_place), 0.0, 0.5 * wall[2]]),
        place=PlaceSpec(position=[x_place, -side * rng.uniform(0.16, 0.32), 0.5 * height]),
    )
