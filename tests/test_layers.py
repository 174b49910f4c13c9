"""The layers hold (docs/layout.md): no module imports one from a layer to its right.

Every module of ``drake_sim``, ``planning`` and ``diagrams`` is parsed (``ast``, imports inside
functions included) and given a layer by the longest matching prefix below; an import of a
project module must land in the same layer or one to its left. ``planning`` has layers of its
own inside, so that its rooms do not import each other in a loop either.
"""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("drake_sim", "planning", "diagrams")

# Left to right. A prefix names a module or a package (and everything in it).
LAYERS = (
    ("base", ("drake_sim", "drake_sim.base")),
    ("descriptions: robots and worlds", ("drake_sim.robots", "drake_sim.worlds")),
    ("systems", ("drake_sim.systems",)),
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
            "planning.plan",
            "planning.planner_options",
            "planning.planner_kernels",
            "planning.motion_planner",
        ),
    ),
    ("planning: execution, interface", ("planning.execution", "planning.interface")),
    ("planning: mobile navigation (costmaps, planners, navigator)", ("planning.mobile",)),
    ("planning: tasks and the public API", ("planning.task", "planning")),
    ("diagrams", ("diagrams",)),
    (
        "apps",
        (
            "drake_sim.flip",
            "drake_sim.flip_run",
            "drake_sim.walle",
            "drake_sim.walle_run",
            "drake_sim.mapping",
            "drake_sim.mapping_run",
            "drake_sim.navigate",
            "drake_sim.sweep",
            "drake_sim.navigation_run",
            "drake_sim.view",
            "drake_sim.pickplace",
            "drake_sim.tools",
            "planning.benchmark",
            "planning.regions",
            "planning._ompl_baseline",
        ),
    ),
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


def project_modules() -> dict[str, Path]:
    modules = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            modules[".".join(parts)] = path
    return modules


def imported_modules(module: str, path: Path) -> set[str]:
    """The project modules ``path`` imports (``from a import b`` counts as ``a.b`` when that is a
    module, else as ``a``)."""
    is_package = path.name == "__init__.py"
    known = project_modules()
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".")
                base = base[: len(base) - node.level + (1 if is_package else 0)]
                origin = ".".join(base + ([node.module] if node.module else []))
            else:
                origin = node.module
            names = [
                f"{origin}.{a.name}" if f"{origin}.{a.name}" in known else origin
                for a in node.names
            ]
        else:
            continue
        found.update(n for n in names if n.split(".")[0] in PACKAGES)
    return found


def test_every_module_has_a_layer():
    for module in project_modules():
        layer_of(module)


def test_layer_of_examples():
    assert LAYERS[layer_of("drake_sim.base.cli")][0] == "base"
    assert LAYERS[layer_of("drake_sim.systems.sensors.imu")][0] == "systems"
    assert LAYERS[layer_of("drake_sim.flip")][0] == "apps"
    assert LAYERS[layer_of("planning.search.rrt")][0] == "planning: search"
    assert LAYERS[layer_of("planning.benchmark")][0] == "apps"
    with pytest.raises(KeyError):
        layer_of("somewhere.else")


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


def test_the_check_catches_an_upward_import(tmp_path, monkeypatch):
    """The check itself can fail: a systems module that imports a diagram is reported."""
    fake = tmp_path / "drake_sim" / "systems" / "bad.py"
    fake.parent.mkdir(parents=True)
    fake.write_text("from diagrams.flip import make_flip_diagram\n")
    found = imported_modules("drake_sim.systems.bad", fake)
    assert "diagrams.flip" in found
    assert layer_of("diagrams.flip") > layer_of("drake_sim.systems.bad")


def test_library_never_imports_tests_or_benchmarks():
    for module, path in project_modules().items():
        text = path.read_text()
        assert "import tests" not in text and "from tests" not in text, module
        assert "from benchmarks" not in text and "import benchmarks" not in text, module
