"""Meshcat display of a planning scene: the robot, world objects, and held objects in another
colour."""

from __future__ import annotations

from pydrake.geometry import Rgba

WORLD_COLOR = Rgba(0.55, 0.55, 0.6, 0.8)
ATTACHED_COLOR = Rgba(0.95, 0.55, 0.1, 0.9)
TABLE_COLOR = Rgba(0.55, 0.4, 0.25, 1.0)
PREFIX = "planning/objects"


def publish_scene(scene, q) -> None:
    """Draws ``scene`` with the robot at q in the scene's Meshcat (nothing without one).

    World objects are grey (the table brown) and held objects orange, each at
    ``planning/objects/<world|attached>/<name>``; objects removed since the last call are deleted.
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
        color = TABLE_COLOR if name == "table" else WORLD_COLOR
        meshcat.SetObject(path, obj.drake_shape(), color)
        meshcat.SetTransform(path, obj.X_PO)
    for name in scene.attached_objects:
        path = f"{PREFIX}/attached/{name}"
        meshcat.SetObject(path, scene.attached_objects[name].drake_shape(), ATTACHED_COLOR)
        meshcat.SetTransform(path, scene.object_pose(name, q))
