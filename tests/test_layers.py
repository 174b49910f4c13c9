"""The layers hold (docs/architecture.md): no module imports one from a layer to its right, and no
modules import each other in a loop.

Every module of ``drake_sim``, ``planning`` and ``diagrams`` is parsed (``ast``, imports inside
functions and type-only ``TYPE_CHECKING`` imports included) and given a layer by the longest
matching prefix below; an import of a project module must land in the same layer or one to its
left. ``planning`` has layers of its own inside, so that its rooms do not import each other in
a loop either. The apps are found where they stand, not listed: every top-level module of
``drake_sim`` (``drake_sim/<app>.py``) and everything in ``drake_sim.sweep`` and
``drake_sim.tools``.

Within a layer imports may go either way, so loops are checked apart: between modules, and
between rooms (a room is a module's first two dotted parts: ``planning.model``,
``drake_sim.systems``, ``diagrams.flip``).
"""

from pathlib import Path

import pytest

from drake_sim.tools import architecture
from drake_sim.tools.architecture import import_graph, project_modules, room_graph


def imported_modules(module: str, path: Path) -> set[str]:
    """The project modules ``path`` imports (``architecture.imported_modules``)."""
    return architecture.imported_modules(module, path, frozenset(project_modules()))


ROOT = Path(__file__).resolve().parent.parent
APP_PACKAGES = ("drake_sim.sweep", "drake_sim.tools")
"""Packages whose every module is an app (besides ``drake_sim``'s top-level modules)."""


def app_prefixes(root: Path = ROOT) -> tuple[str, ...]:
    """The apps by where they stand: ``drake_sim/<name>.py`` (not ``__init__``), and the
    packages of ``APP_PACKAGES``."""
    top = sorted(p.stem for p in (root / "drake_sim").glob("*.py") if p.stem != "__init__")
    return (*(f"drake_sim.{name}" for name in top), *APP_PACKAGES)


# Left to right. A prefix names a module or a package (and everything in it).
LAYERS = (
    ("base", ("drake_sim", "drake_sim.base")),
    ("descriptions: robots and worlds", ("drake_sim.robots", "drake_sim.worlds")),
    ("systems", ("drake_sim.systems",)),
    ("navigation: costmaps, planners, navigator", ("drake_sim.navigation",)),
    (
        "planning: errors, config, model, paths, objects",
        (
            "planning.errors",
            "planning.config",
            "planning.model",
            "planning.paths",
            "planning.scene_objects",
        ),
    ),
    (
        "planning: collision, timing, io, display",
        ("planning.collision", "planning.timing", "planning.io", "planning.scene_display"),
    ),
    ("planning: search", ("planning.search",)),
    (
        "planning: state, scene, plan, planner",
        (
            "planning.robot_state",
            "planning.planning_scene",
            "planning.scene_positions",
            "planning.plan",
            "planning.plan_plot",
            "planning.planner_options",
            "planning.planner_kernels",
            "planning.planner_setup",
            "planning.motion_planner",
        ),
    ),
    ("planning: execution, interface", ("planning.execution", "planning.interface")),
    ("planning: tasks and the public API", ("planning.task", "planning")),
    ("diagrams", ("diagrams",)),
    ("runs: recipes and run harnesses", ("drake_sim.runs",)),
    ("apps", app_prefixes()),
)


def layer_of(module: str) -> int:
    """The index in LAYERS of the longest prefix that names ``module`` or a package holding it."""
    best, best_len = None, -1
    for index, (_, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best_len:
                best, best_len = index, len(prefix)
    if best is None:
        raise KeyError(f"module {module} is in no layer: add it to LAYERS")
    return best


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The import loops of ``graph``: its strongly connected components of more than one node
    (Tarjan's algorithm, iterative), each sorted, in sorted order."""
    nodes = sorted(set(graph) | {t for targets in graph.values() for t in targets})
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found = []
    for root in nodes:
        if root in index:
            continue
        work = [(root, iter(sorted(graph.get(root, ()))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, targets = work[-1]
            for target in targets:
                if target not in index:
                    index[target] = low[target] = len(index)
                    stack.append(target)
                    on_stack.add(target)
                    work.append((target, iter(sorted(graph.get(target, ())))))
                    break
                if target in on_stack:
                    low[node] = min(low[node], index[target])
            else:
                work.pop()
                if work:
                    parent = work[-1][0]
                    low[parent] = min(low[parent], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == node:
                            break
                    if len(component) > 1:
                        found.append(sorted(component))
    return sorted(found)


def test_every_module_has_a_layer():
    for module in project_modules():
        layer_of(module)


def test_layer_of_examples():
    def name(module):
        return LAYERS[layer_of(module)][0]

    assert name("drake_sim") == "base"
    assert name("drake_sim.base.cli") == "base"
    assert name("drake_sim.systems.sensors.imu") == "systems"
    assert name("drake_sim.navigation.costmap") == "navigation: costmaps, planners, navigator"
    assert name("planning.search.rrt") == "planning: search"
    assert name("diagrams.flip") == "diagrams"
    assert name("drake_sim.runs.recipe") == "runs: recipes and run harnesses"
    assert name("drake_sim.flip") == "apps"
    assert name("drake_sim.sweep.spec") == "apps"
    assert name("drake_sim.tools.plan_benchmark") == "apps"
    # planning.benchmark only forwards to the app (runpy, under __main__): part of planning,
    # importing nothing of the project.
    assert name("planning.benchmark") == "planning: tasks and the public API"
    assert imported_modules("planning.benchmark", ROOT / "planning" / "benchmark.py") == set()
    with pytest.raises(KeyError):
        layer_of("somewhere.else")


def test_apps_are_found_where_they_stand(tmp_path):
    (tmp_path / "drake_sim").mkdir()
    for name in ("__init__", "walle", "navigate"):
        (tmp_path / "drake_sim" / f"{name}.py").write_text("")
    assert app_prefixes(tmp_path) == (
        "drake_sim.navigate",
        "drake_sim.walle",
        "drake_sim.sweep",
        "drake_sim.tools",
    )
    apps = set(LAYERS[-1][1])
    assert {"drake_sim.walle", "drake_sim.navigate", "drake_sim.pickplace"} <= apps
    assert "drake_sim" not in apps and "drake_sim.runs" not in apps


def violations() -> list[str]:
    out = []
    for module, path in project_modules().items():
        mine = layer_of(module)
        for target in sorted(imported_modules(module, path)):
            theirs = layer_of(target)
            if theirs > mine:
                out.append(f"{module} ({LAYERS[mine][0]}) imports {target} ({LAYERS[theirs][0]})")
    return out


def test_no_import_runs_back_up_a_layer():
    assert violations() == []


def test_the_check_catches_an_upward_import(tmp_path):
    """The check itself can fail: a systems module that imports a diagram is reported."""
    fake = tmp_path / "drake_sim" / "systems" / "bad.py"
    fake.parent.mkdir(parents=True)
    fake.write_text("from diagrams.flip import make_flip_diagram\n")
    found = imported_modules("drake_sim.systems.bad", fake)
    assert "diagrams.flip" in found
    assert layer_of("diagrams.flip") > layer_of("drake_sim.systems.bad")


def test_no_two_modules_import_each_other():
    assert cycles(import_graph()) == []


def test_no_two_rooms_import_each_other():
    assert cycles(room_graph(import_graph())) == []


def test_the_loop_checks_catch_loops(tmp_path):
    """Loops of two and of three are found, type-only imports count, and rooms loop when
    modules in them do even if no two modules do."""
    fake = tmp_path / "filter.py"
    fake.write_text(
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n"
        "    from drake_sim.systems.estimation.amcl import AmclConfig\n"
    )
    found = imported_modules("drake_sim.systems.estimation.filter", fake)
    assert found == {"drake_sim.systems.estimation.amcl"}
    graph = {
        "a.x.one": {"a.x.two"},
        "a.x.two": {"a.x.one", "b.y.one"},
        "b.y.one": {"c.z.one"},
        "c.z.one": {"b.y.two"},
        "b.y.two": set(),
    }
    assert cycles(graph) == [["a.x.one", "a.x.two"]]
    assert cycles(room_graph(graph)) == [["b.y", "c.z"]]
    assert cycles({"p": {"q"}, "q": {"r"}, "r": {"p"}, "s": {"p"}}) == [["p", "q", "r"]]


def test_library_never_imports_tests_or_benchmarks():
    for module, path in project_modules().items():
        text = path.read_text()
        assert "import tests" not in text and "from tests" not in text, module
        assert "from benchmarks" not in text and "import benchmarks" not in text, module
