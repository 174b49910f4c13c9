"""MoveIt's text scene format (``.scene``, what the MoveIt RViz plugin exports and imports).

The grammar, as MoveIt's ``PlanningScene::loadGeometryFromStream`` reads it (numbers and words
are separated by any white space; the scene name and object names take their whole line)::

    <scene name>
    * <object name>
    [<x> <y> <z>                      the object's pose (newer files only)
     <qx> <qy> <qz> <qw>]
    <shape count>
    <shape count times:>
      box <x> <y> <z> | sphere <radius> | cylinder <radius> <length>
      <x> <y> <z>                     the shape's pose: in the object's frame in newer files,
      <qx> <qy> <qz> <qw>             in the world in older ones
      <r> <g> <b> <a>                 its colour
    [<subframe count>                 (newer files only)
     <subframe count times: name x y z qx qy qz qw>]
    ... more objects ...
    .

A file is newer when the line after its first ``*`` line holds more than one word (a pose,
not a shape count). Objects are in the world frame; one named again replaces the earlier one,
and one of several shapes becomes objects ``name``, ``name#1``, ... Meshes, cones and planes
are not supported; anything after the ``.`` is ignored. As for MoveIt, a file without its name
line (empty, blank, or starting with ``.`` or an object) is malformed; a name line and ``.``
alone is a valid empty scene.
"""

import math

from pydrake.math import RigidTransform

from planning.scene_objects import SceneObject, make_pose

_SIZES = {"box": ("x", "y", "z"), "sphere": ("radius",), "cylinder": ("radius", "length")}
_UNSUPPORTED = ("mesh", "cone", "plane")


def parse_scene_text(text: str, where: str = "scene") -> list[SceneObject]:
    """Returns the objects (in the world frame) of a ``.scene`` text.

    Raises:
        ValueError: naming ``where``, the line and what was expected there.
    """
    lines = text.splitlines()
    if not text.strip():
        raise ValueError(
            f"{where}: empty scene file (expected the scene name on line 1, then its objects "
            "and a '.' line)"
        )
    first = lines[0].strip()
    if first == "." or first.startswith("*"):
        raise ValueError(
            f"{where}:1: expected the scene name, got {first!r} (a scene file starts with its "
            "name line, as MoveIt writes it)"
        )
    newer = _newer_format(lines)
    reader = _Reader(lines, where)
    objects: dict[str, list] = {}
    while (marker := reader.word("'*' (an object) or '.' (the end)")) != ".":
        if marker != "*":
            raise reader.error(f"expected '*' (an object) or '.' (the end), got {marker!r}")
        name = reader.rest_of_line("an object needs a name after '*'")
        X_WO = reader.pose(f"object {name!r}") if newer else RigidTransform()
        shapes = []
        for k in range(reader.count(f"object {name!r}: the number of shapes")):
            what = f"object {name!r}, shape {k + 1}"
            shape, size = reader.shape(what)
            X_S = reader.pose(what)
            reader.numbers(4, f"{what}: colour r g b a")
            shapes.append((shape, size, X_WO @ X_S))
        if newer:
            for _ in range(reader.count(f"object {name!r}: the number of subframes")):
                reader.word(f"object {name!r}: a subframe name")
                reader.pose(f"object {name!r}: subframe")
        if shapes:
            objects[name] = shapes
    return [
        SceneObject(name if k == 0 else f"{name}#{k}", shape, size, X)
        for name, shapes in objects.items()
        for k, (shape, size, X) in enumerate(shapes)
    ]


def _newer_format(lines: list[str]) -> bool:
    for i, line in enumerate(lines[1:], start=1):
        if line.startswith("*"):
            following = lines[i + 1].strip() if i + 1 < len(lines) else ""
            return " " in following
    return False


class _Reader:
    """Words and numbers of the lines after the scene name, with the line number of each."""

    def __init__(self, lines: list[str], where: str):
        self._lines, self._where = lines, where
        self._line, self._pos = 1, 0

    def error(self, message: str) -> ValueError:
        line = min(self._line, len(self._lines) - 1) + 1
        return ValueError(f"{self._where}:{line}: {message}")

    def word(self, what: str) -> str:
        while self._line < len(self._lines):
            text = self._lines[self._line]
            while self._pos < len(text) and text[self._pos].isspace():
                self._pos += 1
            if self._pos < len(text):
                start = self._pos
                while self._pos < len(text) and not text[self._pos].isspace():
                    self._pos += 1
                return text[start : self._pos]
            self._line, self._pos = self._line + 1, 0
        raise self.error(f"expected {what}, got the end of the file (no '.' at the end?)")

    def rest_of_line(self, missing: str) -> str:
        """The rest of the current line, stripped; ``missing`` is the error when it is empty."""
        rest = self._lines[self._line][self._pos :].strip()
        if not rest:
            raise self.error(missing)
        self._line, self._pos = self._line + 1, 0
        return rest

    def numbers(self, count: int, what: str) -> list[float]:
        values = []
        for _ in range(count):
            word = self.word(what)
            try:
                value = float(word)
            except ValueError:
                raise self.error(f"{what}: expected a number, got {word!r}") from None
            if not math.isfinite(value):
                raise self.error(f"{what}: {word!r} is not finite")
            values.append(value)
        return values

    def count(self, what: str) -> int:
        word = self.word(what)
        if not word.isdigit():
            raise self.error(f"{what}: expected a whole number, got {word!r}")
        return int(word)

    def pose(self, what: str) -> RigidTransform:
        position = self.numbers(3, f"{what}: position x y z")
        quaternion = self.numbers(4, f"{what}: orientation qx qy qz qw")
        try:
            return make_pose(position, quaternion, name=what)
        except ValueError as e:
            raise self.error(str(e)) from None

    def shape(self, what: str) -> tuple[str, tuple[float, ...]]:
        kind = self.word(f"{what}: a shape (box, sphere, cylinder)")
        if kind in _UNSUPPORTED:
            raise self.error(f"{what}: {kind} shapes are not supported (box, sphere, cylinder)")
        if kind not in _SIZES:
            raise self.error(f"{what}: unknown shape {kind!r} (box, sphere, cylinder)")
        names = _SIZES[kind]
        size = self.numbers(len(names), f"{what}: {kind} {' '.join(names)}")
        if min(size) <= 0.0:
            raise self.error(f"{what}: {kind} sizes must be positive, got {size}")
        return kind, tuple(size)
