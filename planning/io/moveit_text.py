"""MoveIt's text scene format (``.scene``, what the MoveIt RViz plugin exports and imports).

The grammar, as MoveIt's ``PlanningScene::loadGeometryFromStream`` and geometric_shapes'
``constructShapeFromText`` read it (numbers and words are separated by any white space; the
scene name and object names take their whole line)::

    <scene name>
    * <object name>
    [<x> <y> <z>                      the object's pose (newer files only)
     <qx> <qy> <qz> <qw>]
    <shape count>
    <shape count times:>
      box <x> <y> <z> | sphere <radius> | cylinder <radius> <length> | cone <radius> <length>
      | plane <a> <b> <c> <d>
      | mesh <vertex count> <triangle count> <x y z per vertex> <i j k per triangle>
      <x> <y> <z>                     the shape's pose: in the object's frame in newer files,
      <qx> <qy> <qz> <qw>             in the world in older ones
      <r> <g> <b> <a>                 its colour (all 0: none)
    [<subframe count>                 (newer files only)
     <subframe count times: name x y z qx qy qz qw>]
    ... more objects ...
    .

A file is newer when the line after its first ``*`` line holds more than one word (a pose,
not a shape count). Objects are in the world frame; one named again gets more shapes (MoveIt
adds to it), and an object of several shapes becomes objects ``name``, ``name#1``, ...; the
last colour that is not all 0 is the object's; subframes become frames of ``name``. Meshes and
cones are checked as their convex hulls and planes as a large box behind them
(``planning.io.moveit_shapes``). Anything after the ``.`` is ignored.

As for MoveIt, a file without its name line (empty, blank, or starting with an object) is
malformed, and a name line and ``.`` alone is a valid empty scene. A file that ends where an
object could start, without its ``.`` line (or that is ``.`` alone, which MoveIt reads as the
name of a scene that never ends), loads the objects before the end with a warning: MoveIt keeps
them and reports an error. Anything else that does not follow the grammar is malformed.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from pydrake.math import RigidTransform

from planning.io import moveit_shapes as shapes
from planning.io.moveit_objects import Entry, Issues, flatten
from planning.scene_objects import CONVEX, SceneObject, make_pose

_SIZES = {
    "box": ("x", "y", "z"),
    "sphere": ("radius",),
    "cylinder": ("radius", "length"),
    "cone": ("radius", "length"),
    "plane": ("a", "b", "c", "d"),
}
_KINDS = "box, sphere, cylinder, cone, plane, mesh"


def parse_scene_text(text: str, where: str = "scene", *, strict: bool = False) -> list:
    """Returns the objects (in the world frame) of a ``.scene`` text (``read_scene_text``).

    Raises:
        ValueError: naming ``where``, the line and what was expected there.
    """
    return read_scene_text(text, where, Issues(where, strict))[1]


def read_scene_text(
    text: str,
    where: str = "scene",
    issues: Issues | None = None,
    base: Path | None = None,
    package_paths=None,
) -> tuple[str, list[SceneObject]]:
    """Returns the name and the objects (in the world frame) of a ``.scene`` text.

    Args:
        issues: where warnings go (a new ``Issues(where)`` when None).
        base, package_paths: unused (the text format holds no mesh files); taken for symmetry
            with the YAML reader.

    Raises:
        ValueError: naming ``where``, the line and what was expected there.
    """
    issues = Issues(where) if issues is None else issues
    lines = text.splitlines()
    if not text.strip():
        raise ValueError(
            f"{where}: empty scene file (expected the scene name on line 1, then its objects "
            "and a '.' line)"
        )
    first = lines[0].strip()
    if first.startswith("*"):
        raise ValueError(
            f"{where}:1: expected the scene name, got {first!r} (a scene file starts with its "
            "name line, as MoveIt writes it)"
        )
    if first == "." and not "".join(lines[1:]).strip():
        issues.drop(
            "1",
            "'.' alone (MoveIt reads it as the scene's name, then finds no end): an empty scene",
        )
        return "", []
    newer = _newer_format(lines)
    reader = _Reader(lines, where)
    objects: dict[str, Entry] = {}
    colors: dict[str, tuple] = {}
    while (marker := reader.word("'*' (an object) or '.' (the end)", end_ok=True)) != ".":
        if marker is None:
            issues.drop(
                str(len(lines)),
                "no '.' line at the end: the objects before it are "
                "loaded (MoveIt loads them and reports an error)",
            )
            break
        if marker != "*":
            raise reader.error(f"expected '*' (an object) or '.' (the end), got {marker!r}")
        name = reader.rest_of_line("an object needs a name after '*'")
        _read_object(reader, name, newer, objects, colors, issues)
    return lines[0].strip(), flatten(objects, colors)


def _read_object(reader, name: str, newer: bool, objects: dict, colors: dict, issues) -> None:
    X_WO = reader.pose(f"object {name!r}") if newer else RigidTransform()
    pieces = []
    for k in range(reader.count(f"object {name!r}: the number of shapes")):
        what = f"object {name!r}, shape {k + 1}"
        line = reader.line_number()
        make = reader.shape(what)
        X_OS = reader.pose(what)
        color = tuple(reader.numbers(4, f"{what}: colour r g b a"))
        try:
            pieces.append(make(X_OS, X_WO.inverse().translation()))
        except shapes.UnrepresentableError as e:
            issues.drop(str(line), f"{what} skipped: {e}", None if pieces else name)
        if any(c > 0.0 for c in color):
            colors[name] = tuple(min(max(c, 0.0), 1.0) for c in color)
    subframes = {}
    if newer:
        for _ in range(reader.count(f"object {name!r}: the number of subframes")):
            subframe = reader.word(f"object {name!r}: a subframe name")
            subframes[subframe] = reader.pose(f"object {name!r}: subframe {subframe!r}")
    if name in objects:  # named again: more shapes, the new pose (MoveIt's addToObject)
        old = objects[name]
        X_new = X_WO if newer else old.X_WO
        old.pieces.extend(p.at(X_new.inverse() @ X_WO @ p.X_OS) for p in pieces)
        old.X_WO = X_new
        old.subframes.update(subframes)
    elif pieces:
        objects[name] = Entry(X_WO, pieces, subframes)


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

    def word(self, what: str, end_ok: bool = False) -> str | None:
        """The next word; at the end of the file None when ``end_ok``, else an error."""
        if self._skip():
            text, start = self._lines[self._line], self._pos
            while self._pos < len(text) and not text[self._pos].isspace():
                self._pos += 1
            return text[start : self._pos]
        if end_ok:
            return None
        raise self.error(f"expected {what}, got the end of the file (no '.' at the end?)")

    def _skip(self) -> bool:
        """Moves to the next word; False at the end of the file."""
        while self._line < len(self._lines):
            text = self._lines[self._line]
            while self._pos < len(text) and text[self._pos].isspace():
                self._pos += 1
            if self._pos < len(text):
                return True
            self._line, self._pos = self._line + 1, 0
        return False

    def line_number(self) -> int:
        """The line (from 1) of the next word."""
        self._skip()
        return min(self._line, len(self._lines) - 1) + 1

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

    def shape(self, what: str):
        """Reads a shape; returns ``make(X_OS, p_O_origin) -> moveit_shapes.Piece`` (which
        raises ``UnrepresentableError`` for a mesh without volume or area)."""
        kind = self.word(f"{what}: a shape ({_KINDS})")
        if kind == "mesh":
            return self._mesh(what)
        if kind not in _SIZES:
            raise self.error(f"{what}: unknown shape {kind!r} ({_KINDS})")
        names = _SIZES[kind]
        size = tuple(self.numbers(len(names), f"{what}: {kind} {' '.join(names)}"))
        if kind == "plane":
            if not any(size[:3]):
                raise self.error(f"{what}: a plane's normal (a, b, c) is zero")
            return lambda X_OS, near: shapes.plane(list(size), X_OS, near, what)
        if min(size) <= 0.0:
            raise self.error(f"{what}: {kind} sizes must be positive, got {list(size)}")
        return lambda X_OS, near: shapes.solid(kind, size, X_OS)

    def _mesh(self, what: str):
        vertex_count = self.count(f"{what}: mesh vertex count")
        triangle_count = self.count(f"{what}: mesh triangle count")
        points = np.reshape(self.numbers(3 * vertex_count, f"{what}: mesh vertex x y z"), (-1, 3))
        used = set()
        for _ in range(3 * triangle_count):
            index = self.count(f"{what}: mesh triangle vertex index")
            if index >= vertex_count:
                raise self.error(f"{what}: vertex index {index} of {vertex_count} vertices")
            used.add(index)
        if not used:
            return lambda X_OS, near: _empty_mesh()
        points = points[sorted(used)]
        return lambda X_OS, near: shapes.Piece(CONVEX, (), X_OS, shapes.hull_vertices(points))


def _empty_mesh():
    raise shapes.UnrepresentableError("an empty mesh (no triangles)")
