"""Every library module has its own test file, at the mirrored path: the tests of
``planning/search/rrt.py`` are in ``tests/planning/search/test_rrt.py``."""

from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("drake_sim", "planning", "diagrams")


def test_every_module_has_its_own_test_file():
    missing = []
    for package in PACKAGES:
        for module in sorted((ROOT / package).rglob("*.py")):
            if module.name == "__init__.py":
                continue
            relative = module.relative_to(ROOT)
            test_file = ROOT / "tests" / relative.parent / f"test_{module.name.lstrip('_')}"
            if not test_file.is_file():
                missing.append(f"{relative} -> {test_file.relative_to(ROOT)}")
    assert missing == [], "modules without their own test file:\n" + "\n".join(missing)
