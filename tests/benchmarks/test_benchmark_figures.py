"""The ``--json`` figures of the benchmark scripts, from fake measurements (nothing is
simulated or timed): each table renders in docs/benchmarks.md, every column has a value, and
the figures the report's headlines read are there."""

import importlib.util
from pathlib import Path
from types import SimpleNamespace

import pytest

from benchmarks import report as report_mod
from benchmarks import report_markdown as md

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def load(monkeypatch):
    """Loads ``benchmarks/<name>_benchmark.py`` as ``python benchmarks/X.py`` would see it."""
    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))

    def load(name):
        path = ROOT / "benchmarks" / f"{name}_benchmark.py"
        spec = importlib.util.spec_from_file_location(f"{name}_benchmark", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module

    return load


def check(result: dict, section: str) -> dict:
    """Every table renders with a value in each column; the section's headline has its
    figures; returns the result."""
    assert set(result) == {"settings", "figures", "tables"}
    for table in result["tables"]:
        text = md.render_table(table)
        assert text.count("\n| ") == len(table["rows"]) + 1  # the header and each row
        for key, *_ in table["columns"]:
            assert any(row.get(key) is not None for row in table["rows"]), key
    for headline in report_mod.HEADLINES:
        if headline.section == section:
            assert md.headline_values(headline, result), headline.text
    return result


def test_flip(load):
    mut = load("flip")
    rows = [{key: float(i) for _, key, _ in mut.COLUMNS} for i in (3, 1, 2)]
    result = check(mut.figures(rows, 20.0), "flip")
    assert result["figures"]["real_time_factor"] == 2.0
    assert result["settings"] == {"runs": 3, "duration_s": 20.0}
    assert result["tables"][0]["rows"][-1]["run"] == "median"


def test_walle(load):
    mut = load("walle")
    lap = SimpleNamespace(sim_time_s=25.0, wall_time_s=10.0, real_time_factor=2.5, end="lap")
    course = {key: 1.0 for _, key, _ in mut.COLUMNS} | {"laps": 1, "end": "lap"}
    result = check(mut.figures({"runs": 2}, [lap, lap], {"oval": course}), "walle")
    assert result["figures"]["real_time_factor"] == 2.5
    assert result["tables"][1]["rows"][0]["course"] == "oval"


def test_walle_balance(load):
    mut = load("walle_balance")
    rows = {
        c: {"push forward (m g)": 0.5, "max |pitch| (deg)": 1.0, "real-time factor": f}
        for c, f in (("pid", 3.0), ("lqr", 4.0))
    }
    settings = {"duration_s": 20.0, "runs": 3, "steps": 8, "push_duration_s": 0.2}
    result = check(mut.figures(rows, settings | {"settle_s": 4.0}), "walle_balance")
    table = result["tables"][0]["rows"]
    assert table[0] == {"figure": "push forward", "unit": "m g", "pid": 0.5, "lqr": 0.5}
    assert table[2]["unit"] == "x"
    assert result["figures"] == {"real_time_factor_pid": 3.0, "real_time_factor_lqr": 4.0}


def test_pickplace(load):
    mut = load("pickplace")
    done = {"success": True, "place_error_m": 0.002, "planning_time_s": 0.3}
    failed = {"success": False, "planning_time_s": 0.1, "failed_step": "lift", "reason": "x"}
    rows = [done | {"real_time_factor": 2.0}, failed | {"real_time_factor": None}]
    summaries = [
        mut.summarize("physics", "default x2", rows),
        mut.summarize("kinematic", "default x2", [done | {"real_time_factor": 5.0}] * 2),
    ]
    assert summaries[0]["success"] == "1/2" and summaries[0]["failures"] == ["lift: x"]
    assert summaries[0]["place_error_median_mm"] == pytest.approx(2.0)
    result = check(mut.figures(summaries, {"repeats": 2}), "pickplace")
    assert result["figures"]["success_rate"] == 1.0  # the kinematic mode's
    assert "physics, default x2: lift: x" in result["tables"][0]["note"]


def test_pick_sequence(load):
    mut = load("pick_sequence")
    rows = [{name: t for name in mut.STEPS} for t in (0.001, 0.002, 0.010)]
    result = check(mut.figures(rows), "pick_sequence")
    assert result["figures"]["total_ms"] == pytest.approx(10.0)  # 5 steps x 2 ms
    assert result["tables"][0]["rows"][-1]["max_ms"] == pytest.approx(50.0)


def test_scene_scale(load):
    mut = load("scene_scale")
    results = {n: {"add": n * 1e-5, "first query": 0.1, "add + query": 0.001} for n in (10, 40)}
    for r in results.values():
        r["Drake add"] = 0.002
    result = check(mut.figures(results), "scene_scale")
    assert result["figures"]["add_ratio"] == pytest.approx(4.0)
    assert "4.00x the one at 10" in result["tables"][0]["note"]


def test_slam(load):
    mut = load("slam")
    row = {key: 1.0 for key, *_ in mut.COLUMNS[1:]} | {"scans": 10}
    result = check(mut.figures([{"arena": "room", **row}], 1), "slam")
    assert result["figures"]["room_update_ms"] == 1.0


def test_amcl(load):
    mut = load("amcl")
    row = {"arena": "room", "fixed_ms": 4.0, "fixed_p95_ms": 6.0, "shipped_ms": 3.0}
    row |= {"settled_s": [1.2, None], "max_error_m": 0.01, "max_error_deg": 0.2}
    global_row = {"arena": "room", "particles": 8000, "settled_s": [4.4], "first_update_ms": 30.0}
    result = check(mut.figures([row], global_row, 2), "amcl")
    assert "| 1.2, - |" in md.render_table(result["tables"][0])


def test_mapping(load):
    mut = load("mapping")
    runs = [
        {key: 0.9 + 0.01 * seed for key, *_ in mut.RUN_COLUMNS} | {"arena": "room", "seed": seed}
        for seed in range(3)
    ]
    for run in runs:
        run["accepted"] = True
    arenas = [{"arena": "room", "real_time_factor": 0.91, "all_accepted": True, "lidar_ms": 0.4}]
    result = check(mut.figures(runs, arenas, {"runs": 3}), "mapping")
    assert result["figures"]["min_map_iou"] == pytest.approx(0.9)
    assert result["figures"]["real_time_factor"] == pytest.approx(0.91)


def test_navigation(load):
    mut = load("navigation")
    runs = [
        {"run": str(i), "sim_time_s": 100.0, "wall_time_s": 20.0, "real_time_factor": float(i)}
        | {"reached": "4/4"}
        for i in (1, 2, 3)
    ]
    arena = {key: 1.0 for key, *_ in mut.ARENA_COLUMNS} | {"arena": "maze", "collisions": 0}
    result = check(mut.figures(runs, [arena], 4.2, {"runs": 3, "goals": 4}), "navigation")
    assert result["figures"] == {"real_time_factor": 2.0, "amcl_update_ms": 4.2}
    assert "4.20 ms per update" in result["tables"][1]["note"]


def test_sweep(load):
    mut = load("sweep")
    result = check(mut.figures({1: (20.0, 16.0), 2: (12.0, 19.0)}, 20), "sweep")
    assert result["figures"]["speedup"] == pytest.approx(20.0 / 12.0)
    rows = result["tables"][0]["rows"]
    assert rows[0]["overhead_s"] == pytest.approx(4.0) and "overhead_s" not in rows[1]
