"""``python -m drake_sim.tools.architecture``: the project's import graph, and its picture.

Every module of ``drake_sim``, ``planning`` and ``diagrams`` is parsed (``ast``: imports at the
top, inside functions and under ``if TYPE_CHECKING:`` alike). ``tests/test_layers.py`` checks the
layers and the loops on this graph; this command draws it between rooms (a room is a module's
first two dotted parts: ``planning.model``, ``drake_sim.systems``) with Graphviz's ``dot``, as
``docs/images/architecture.svg`` (or ``--out FILE``): the picture in docs/architecture.md.
"""

import ast
import shutil
import subprocess
import sys
from pathlib import Path

from drake_sim.base import cli
from drake_sim.base.errors import ConfigError
from drake_sim.base.files import write_atomic

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("drake_sim", "planning", "diagrams")
COLOURS = {"drake_sim": "#dbeafe", "planning": "#fde68a", "diagrams": "#d1fae5"}


def project_modules(root: Path = ROOT) -> dict[str, Path]:
    """Dotted module name -> file, for every module of ``PACKAGES`` (a package is its
    ``__init__``)."""
    modules = {}
    for package in PACKAGES:
        for path in sorted((root / package).rglob("*.py")):
            parts = path.relative_to(root).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            modules[".".join(parts)] = path
    return modules


def imported_modules(module: str, path: Path, known) -> set[str]:
    """The project modules ``path`` imports (``from a import b`` counts as ``a.b`` when that is a
    module of ``known``, else as ``a``), wherever the import stands."""
    is_package = path.name == "__init__.py"
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            origin = node.module
            if node.level:
                base = module.split(".")
                base = base[: len(base) - node.level + (1 if is_package else 0)]
                origin = ".".join(base + ([node.module] if node.module else []))
            names = [
                f"{origin}.{a.name}" if f"{origin}.{a.name}" in known else origin
                for a in node.names
            ]
        else:
            continue
        found.update(n for n in names if n.split(".")[0] in PACKAGES)
    return found


def import_graph(root: Path = ROOT) -> dict[str, set[str]]:
    """Module -> the other project modules it imports."""
    modules = project_modules(root)
    known = frozenset(modules)
    return {
        module: {t for t in imported_modules(module, path, known) if t != module}
        for module, path in modules.items()
    }


def room_of(module: str) -> str:
    """A module's room: its first two dotted parts."""
    return ".".join(module.split(".")[:2])


def room_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """Room -> the other rooms its modules import."""
    rooms: dict[str, set[str]] = {}
    for module, targets in graph.items():
        mine = room_of(module)
        rooms.setdefault(mine, set()).update(room_of(t) for t in targets if room_of(t) != mine)
    return rooms


def dot_source(rooms: dict[str, set[str]]) -> str:
    """Graphviz source: one box per room (coloured by package), an arrow per import, drawn
    from the importer down to what it imports; only the arrows no shorter path implies."""
    reach = {room: _reachable(rooms, room) for room in rooms}
    lines = [
        "digraph architecture {",
        '  rankdir=BT; node [shape=box, style="rounded,filled", fontname=Helvetica, fontsize=11];',
        '  edge [color="#64748b", arrowsize=0.6];',
    ]
    for room in sorted(rooms):
        lines.append(f'  "{room}" [fillcolor="{COLOURS[room.split(".")[0]]}"];')
    for room in sorted(rooms):
        for target in sorted(rooms[room]):
            implied = any(target in reach[other] for other in rooms[room] if other != target)
            if not implied:
                lines.append(f'  "{room}" -> "{target}";')
    lines.append("}")
    return "\n".join(lines) + "\n"


def _reachable(rooms: dict[str, set[str]], start: str) -> set[str]:
    seen, todo = set(), [start]
    while todo:
        for target in rooms.get(todo.pop(), ()):
            if target not in seen:
                seen.add(target)
                todo.append(target)
    return seen


def main(argv=None) -> int:
    parser = cli.ArgumentParser(
        prog="python -m drake_sim.tools.architecture", description=__doc__.split("\n")[0]
    )
    parser.add_argument(
        "--out",
        type=cli.output_file("picture"),
        default=ROOT / "docs" / "images" / "architecture.svg",
        help="SVG to write (default docs/images/architecture.svg)",
    )
    parser.add_argument("--dot", action="store_true", help="print the Graphviz source instead")
    args = parser.parse_args(argv)
    source = dot_source(room_graph(import_graph()))
    if args.dot:
        print(source, end="")
        return cli.EXIT_OK
    if shutil.which("dot") is None:
        raise ConfigError("Graphviz's dot is not installed (apt install graphviz): try --dot")
    svg = subprocess.run(["dot", "-Tsvg"], input=source, capture_output=True, text=True, check=True)
    write_atomic(args.out, svg.stdout, "picture")
    print(f"wrote {args.out}")
    return cli.EXIT_OK


if __name__ == "__main__":
    sys.exit(cli.run(main))
