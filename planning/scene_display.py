"""Meshcat display of a planning scene: the robot, world objects, and held objects in another
colour.

An object with a colour of its own (``SceneObject.color``: a MoveIt scene's ``object_colors``,
or the colour of its shapes in a ``.scene`` file) is drawn in it; the others are grey (the table
brown) in the world and orange in the hand. A convex object (a mesh, a cone) is drawn as the
hull it is checked as.
"""

from __future__ import annotations

from pydrake.geometry import Rgba

WORLD_COLOR = Rgba(0.55, 0.55, 0.6, 0.8)
ATTACHED_COLOR = Rgba(0.95, 0.55, 0.1, 0.9)
TABLE_COLOR = Rgba(0.55, 0.4, 0.25, 1.0)
PREFIX = "planning/objects"


def object_color(obj, default: Rgba) -> Rgba:
    """The colour an object is drawn in: its own, else ``default``."""
    return default if obj.color is None else Rgba(*obj.color)


def publish_scene(scene, q) -> None:
    """Draws ``scene`` with the robot at q in the scene's Meshcat (nothing without one).

    World objects are at ``planning/objects/world/<name>``, held ones at
    ``planning/objects/attached/<name>``, each in its colour (see the module's docstring);
    objects removed since the last call are deleted.
    """
    meshcat = scene.meshcat
    if meshcat is None:
        return
    diagram = scene.model.diagram
    context = diagram.CreateDefaultContext()
    diagram.plant().SetPositions(
        diagram.GetMutableSubsystemContext(diagram.plant(), context), scene.full_q(q)
    )
    diagram.ForcedPublish(context)
    meshcat.Delete(PREFIX)
    for name, obj in scene.world_objects.items():
        path = f"{PREFIX}/world/{name}"
        color = object_color(obj, TABLE_COLOR if name == "table" else WORLD_COLOR)
        meshcat.SetObject(path, obj.drake_shape(), color)
        meshcat.SetTransform(path, obj.X_PO)
    for name, obj in scene.attached_objects.items():
        path = f"{PREFIX}/attached/{name}"
        meshcat.SetObject(path, obj.drake_shape(), object_color(obj, ATTACHED_COLOR))
        meshcat.SetTransform(path, scene.object_pose(name, q))
