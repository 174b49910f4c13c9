"""benchmarks/report.py and report_markdown.py with fake figures: the document, the README's
block, --only keeping the other sections, the MBM summary, failures and bad input. No benchmark
runs here."""

import json

import pytest

from benchmarks import report as mut
from benchmarks import report_markdown as md
from drake_sim.base.errors import ConfigError

MACHINE = {
    "cpu": "Test CPU 3000",
    "cores": 2,
    "memory_gib": 15.6,
    "os": "Debian GNU/Linux 12 (bookworm)",
    "kernel": "Linux 6.1 x86_64",
    "python": "3.11.7",
    "packages": {"drake": "1.45.0", "numpy": "2.0.0", "numba": "0.60.0", "scipy": None},
}
README = f"# Project\n\nIntro.\n\n{md.START_MARKER}\nold figures\n{md.END_MARKER}\n\nMore text.\n"


def fake_figures(section: mut.Section, value: float = 16.4) -> dict:
    """A record like measure's, with every figure a headline may ask for."""
    figures = {
        "real_time_factor": value,
        "planning_time_s": 0.25,
        "success_rate": 1.0,
        "total_ms": 36.5,
        "median_ms": 0.74,
        "p95_ms": 3.3,
        "solved": 34,
        "valid": 35,
        "min_map_iou": 0.987,
    }
    settings = {"runs": 3, "duration_s": 20.0, "repeats": 5, "limit": "20"}
    table = {
        "title": f"{section.title} runs",
        "columns": [
            ["run", "run", "", ""],
            ["real_time_factor", "real-time factor", "x", ".1f"],
            ["ok", "ok", "", ""],
            ["errors_m", "errors", "m", ".3f"],
        ],
        "rows": [
            {"run": "1", "real_time_factor": value, "ok": True, "errors_m": [0.0123, None]},
            {"run": "median", "real_time_factor": value},
        ],
        "note": "A note | with a bar.",
    }
    return {
        "title": section.title,
        "command": "python " + " ".join(section.argv),
        "measured_utc": "2026-11-29T07:41:05Z",
        "wall_time_s": 72.4,
        "cpu_time_s": 61.2,
        "load_average": 3.25,
        "machine": MACHINE,
        "settings": settings,
        "figures": figures,
        "tables": [table],
    }


@pytest.fixture
def paths(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text(README)
    doc = tmp_path / "docs" / "benchmarks.md"
    store = tmp_path / "docs" / "benchmarks.json"
    return {"doc": doc, "store": store, "readme": readme}


def argv(paths, *more):
    return ["--doc", str(paths["doc"]), "--store", str(paths["store"])] + [
        "--readme",
        str(paths["readme"]),
        *more,
    ]


def test_a_table_has_units_in_its_headers_and_formatted_cells():
    table = fake_figures(mut.SECTIONS[0])["tables"][0]
    text = md.render_table(table)
    lines = text.splitlines()
    assert lines[0] == "**Flipping robot runs**"
    assert lines[2] == "| run | real-time factor (x) | ok | errors (m) |"
    assert lines[3] == "|---|---:|---|---|"
    assert lines[4] == "| 1 | 16.4 | yes | 0.012, - |"
    assert lines[5] == "| median | 16.4 | - | - |"
    assert lines[-1] == "A note | with a bar."
    assert md.format_cell("a|b") == "a\\|b"
    assert md.format_cell(float("nan"), ".2f") == "-"
    assert md.format_cell(float("inf"), ".2f") == "inf"
    assert md.format_cell(3, "d") == "3"


def test_slugs_are_githubs_heading_anchors():
    assert md.slug("Wall-E line following") == "wall-e-line-following"
    assert md.slug("Costmaps and the global planner") == "costmaps-and-the-global-planner"
    assert md.slug("Pick-and-place motion planning") == "pick-and-place-motion-planning"
    assert md.slug("AMCL (alone)") == "amcl-alone"


def test_the_document_states_the_machine_dates_commands_and_every_section():
    records = {s.name: fake_figures(s) for s in mut.SECTIONS[:3]}
    text = md.render_document(mut.SECTIONS, records)
    assert text.startswith("# Benchmarks\n")
    assert "| CPU | Test CPU 3000, 2 cores |" in text
    assert "| memory | 15.6 GiB |" in text
    assert "| drake | 1.45.0 |" in text and "| scipy | not installed |" in text
    assert "| Python | 3.11.7 |" in text
    assert "Measured 2026-11-29 07:41 UTC on:" in text
    assert "| OS | Debian GNU/Linux 12 (bookworm) |\n| kernel | Linux 6.1 x86_64 |" in text
    assert (
        "`python benchmarks/flip_benchmark.py --runs 3`: measured 2026-11-29 07:41 UTC, "
        "1 min 12 s of wall time (1 min 1 s of CPU time), load average 3.2 at the start." in text
    )
    for section in mut.SECTIONS:  # every section has its heading and a contents line
        assert f"\n## {section.title}\n" in text
        assert f"- [{section.title}](#{md.slug(section.title)}) (`--only {section.name}`" in text
    assert text.count("Not measured yet") == len(mut.SECTIONS) - 3
    assert "this VM" not in text


def test_a_section_measured_on_another_machine_names_it():
    records = {s.name: fake_figures(s) for s in mut.SECTIONS[:2]}
    other = dict(MACHINE, cpu="Older CPU", cores=4)
    records["flip"] = dict(records["flip"], machine=other, measured_utc="2026-11-01T10:00:00Z")
    text = md.render_document(mut.SECTIONS, records)
    assert "Machine: Older CPU, 4 cores, 15.6 GiB, Debian GNU/Linux 12 (bookworm)." in text
    assert "| CPU | Test CPU 3000, 2 cores |" in text  # the latest section's machine on top
    assert "Measured from 2026-11-01 10:00 UTC to 2026-11-29 07:41 UTC on:" in text


def test_the_readme_block_has_the_headlines_linking_to_their_sections():
    records = {s.name: fake_figures(s) for s in mut.SECTIONS}
    block = md.render_readme_block(mut.SECTIONS, records, mut.HEADLINES, "docs/benchmarks.md")
    assert "[Flipping robot](docs/benchmarks.md#flipping-robot) | 16.4x real time (20 simulated s, median of 3 runs) |" in block  # fmt: skip  # noqa: E501
    assert "median 0.74 ms, p95 3.3 ms per problem, 34 of the 35 valid problems solved" in block
    assert "2026-11-29 (UTC) by `python -m benchmarks.report` on Test CPU 3000, 2 cores" in block
    assert block.count("](docs/benchmarks.md#") == len(mut.HEADLINES)
    del records["walle"]["figures"]["real_time_factor"]  # a missing figure drops its line
    block = md.render_readme_block(mut.SECTIONS, records, mut.HEADLINES, "docs/benchmarks.md")
    assert "wall-e-line-following" not in block
    assert block.count("](docs/benchmarks.md#") == len(mut.HEADLINES) - 1
    empty = md.render_readme_block(mut.SECTIONS, {}, mut.HEADLINES, "docs/benchmarks.md")
    assert empty.startswith("No benchmark figures yet")


def test_only_the_block_between_the_markers_is_replaced():
    replaced = md.replace_block(README, "new | table")
    assert replaced == README.replace("old figures", "new | table")
    assert md.replace_block(replaced, "again") == README.replace("old figures", "again")
    assert md.replace_block("# no markers\n", "x") is None
    assert md.replace_block(f"{md.END_MARKER}\n{md.START_MARKER}\n", "x") is None
    assert md.replace_block(README + md.START_MARKER, "x") is None


def test_only_re_measures_the_named_sections_and_keeps_the_others(paths, monkeypatch, capsys):
    calls = []

    def measure(section, mbm_dataset=None):
        calls.append(section.name)
        return fake_figures(section, value=16.4 if len(calls) <= len(mut.SECTIONS) else 99.0)

    monkeypatch.setattr(mut, "measure", measure)
    assert mut.main(argv(paths)) == 0
    assert calls == list(mut.NAMES)
    first = json.loads(paths["store"].read_text())["sections"]
    assert list(first) == list(mut.NAMES)

    assert mut.main(argv(paths, "--only", "walle", "flip")) == 0
    assert calls[len(mut.NAMES) :] == ["flip", "walle"]  # in the report's order
    second = json.loads(paths["store"].read_text())["sections"]
    assert second["flip"]["figures"]["real_time_factor"] == 99.0
    assert second["walle"]["figures"]["real_time_factor"] == 99.0
    kept = [name for name in mut.NAMES if name not in ("flip", "walle")]
    assert kept and all(second[name] == first[name] for name in kept)
    text = paths["doc"].read_text()
    assert "| 1 | 99.0 | yes |" in text and "| 1 | 16.4 | yes |" in text
    readme = paths["readme"].read_text()
    assert readme.startswith("# Project\n\nIntro.\n\n" + md.START_MARKER + "\n")
    assert readme.endswith(md.END_MARKER + "\n\nMore text.\n")
    assert "old figures" not in readme
    assert "[Flipping robot](docs/benchmarks.md#flipping-robot) | 99.0x real time" in readme
    assert "stopped" not in capsys.readouterr().err


def test_no_run_writes_the_document_and_block_again_from_the_stored_figures(paths, monkeypatch):
    monkeypatch.setattr(mut, "measure", lambda section, mbm_dataset=None: fake_figures(section))
    paths["readme"].write_text("# Project\n")  # the markers come later
    assert mut.main(argv(paths, "--only", "flip")) == 0
    stored = paths["store"].read_text()
    paths["readme"].write_text(README)
    paths["doc"].unlink()
    monkeypatch.setattr(mut, "measure", lambda *a: pytest.fail("nothing should run"))
    assert mut.main(argv(paths, "--no-run")) == 0
    assert "16.4x real time" in paths["readme"].read_text()
    assert "## Flipping robot" in paths["doc"].read_text()
    assert paths["store"].read_text() == stored


def test_a_readme_without_markers_is_left_as_it_was_with_a_warning(paths, monkeypatch, capsys):
    monkeypatch.setattr(mut, "measure", lambda section, mbm_dataset=None: fake_figures(section))
    paths["readme"].write_text("# Project\n")
    assert mut.main(argv(paths, "--only", "flip")) == 0
    assert paths["readme"].read_text() == "# Project\n"
    assert "warning:" in capsys.readouterr().err
    assert "## Flipping robot" in paths["doc"].read_text()


def test_a_failed_section_keeps_its_figures_and_says_why(paths, monkeypatch, capsys):
    monkeypatch.setattr(mut, "measure", lambda section, mbm_dataset=None: fake_figures(section))
    assert mut.main(argv(paths, "--only", "flip", "costmap")) == 0

    def failing(section, mbm_dataset=None):
        raise mut.SectionError("exit code 1: out of memory")

    monkeypatch.setattr(mut, "measure", failing)
    assert mut.main(argv(paths, "--only", "flip", "lidar")) == 1
    err = capsys.readouterr().err
    assert "error: failed: flip, lidar (previous figures kept)" in err
    stored = json.loads(paths["store"].read_text())["sections"]
    assert stored["flip"]["figures"]["real_time_factor"] == 16.4
    assert stored["flip"]["last_failure"]["reason"] == "exit code 1: out of memory"
    assert "tables" not in stored["lidar"]
    text = paths["doc"].read_text()
    assert text.count("failed: exit code 1: out of memory") == 2
    assert "| 1 | 16.4 | yes |" in text  # flip's previous figures
    assert "Not measured yet: `python -m benchmarks.report --only lidar`." in text


def test_a_stop_keeps_what_was_measured(paths, monkeypatch):
    def measure(section, mbm_dataset=None):
        if section.name == "walle":
            raise KeyboardInterrupt
        return fake_figures(section)

    monkeypatch.setattr(mut, "measure", measure)
    assert mut.main(argv(paths)) == 0
    stored = json.loads(paths["store"].read_text())["sections"]
    assert list(stored) == ["flip", "sweep"]


def test_bad_input_is_one_clear_error(paths, monkeypatch):
    monkeypatch.setattr(mut, "measure", lambda *a: pytest.fail("nothing should run"))
    with pytest.raises(ConfigError, match="invalid choice"):
        mut.main(argv(paths, "--only", "nonsense"))
    paths["store"].parent.mkdir(parents=True)
    paths["store"].write_text("{not json")
    with pytest.raises(ConfigError, match="cannot be read as benchmark figures"):
        mut.main(argv(paths, "--only", "flip"))
    paths["store"].write_text('{"other": 1}')
    with pytest.raises(ConfigError, match="not a benchmark figures file"):
        mut.main(argv(paths, "--only", "flip"))
    with pytest.raises(ConfigError, match="drop --only"):
        mut.main(argv(paths, "--no-run", "--only", "flip"))
    paths["store"].unlink()
    with pytest.raises(ConfigError, match="no stored figures"):
        mut.main(argv(paths, "--no-run"))
    assert mut.main(["--list"]) == 0


def test_non_finite_figures_are_stored_as_null():
    record = fake_figures(mut.SECTIONS[0], value=float("inf"))
    record["figures"]["settled_s"] = [1.0, float("nan")]
    data = json.loads(mut.store_text({"flip": record, "unknown": {}}))
    assert data["sections"]["flip"]["figures"]["real_time_factor"] is None
    assert data["sections"]["flip"]["figures"]["settled_s"] == [1.0, None]
    assert list(data["sections"]) == ["flip"]


def test_the_mbm_rows_are_summarised_per_family_and_in_all():
    rows = [
        {"family": "box", "valid": True, "success": True, "time_s": 0.001, "path_length": 4.0}
        | {"path_valid_fine": True},
        {"family": "box", "valid": True, "success": False, "time_s": 5.0, "path_length": None},
        {"family": "box", "valid": False, "success": False, "time_s": None},
        {"family": "cage", "valid": True, "success": True, "time_s": 0.003, "path_length": 6.0}
        | {"path_valid_fine": False},
    ]
    figures = mut.mbm_figures(rows, limit="5")
    table = figures["tables"][0]["rows"]
    assert [r["family"] for r in table] == ["box", "cage", "all"]
    box, cage, every = table
    assert (box["problems"], box["valid"], box["solved"], box["fine_ok"]) == (3, 2, 1, 1)
    assert box["median_ms"] == pytest.approx(2500.5)
    assert box["median_length"] == 4.0
    assert (cage["solved"], cage["fine_ok"]) == (1, 0)
    assert (every["problems"], every["valid"], every["solved"]) == (4, 3, 2)
    assert every["median_ms"] == pytest.approx(3.0)
    assert figures["figures"] == {
        "median_ms": every["median_ms"],
        "p95_ms": every["p95_ms"],
        "valid": 3,
        "solved": 2,
        "problems": 4,
    }
    assert figures["settings"] == {"limit": "5"}
    assert mut.mbm_figures({"rows": rows})["figures"]["solved"] == 2  # the object form
    with pytest.raises(ValueError, match="no rows"):
        mut.mbm_figures({"joint_names": []})


def test_the_machine_is_described():
    machine = mut.machine()
    assert machine["cores"] >= 1 and machine["cpu"]
    assert machine["python"].count(".") == 2
    assert set(machine["packages"]) == set(mut.PACKAGES)
    assert machine["packages"]["numpy"]  # installed wherever the tests run


def test_the_commands_are_the_benchmarks_own():
    for section in mut.SECTIONS:
        argv = mut.command_argv(section)
        if argv[0] == "-m":
            assert argv[1] == "planning.benchmark" and section.output == "--report"
        else:
            assert (mut.ROOT / argv[0]).is_file(), argv[0]
            assert section.output == "--json"
            assert "--json" in (mut.ROOT / argv[0]).read_text()
    dataset = mut.command_argv(mut.SECTIONS[mut.NAMES.index("mbm")], mbm_dataset="/data/mbm")
    assert dataset[-2:] == ["--dataset", "/data/mbm"]


def _section(code: str, *args: str, output: str = "--json") -> mut.Section:
    """A section whose command is ``python -c CODE ARGS OUTPUT FILE`` (FILE is sys.argv[-1])."""
    return mut.Section("fake", "Fake", ("-c", code, *args), "A fake benchmark.", output=output)


WRITE = "import json, sys; open(sys.argv[-1], 'w').write(json.dumps({}))"


def test_measure_runs_the_command_and_keeps_its_figures_with_the_date_and_machine():
    figures = {"settings": {"n": 1}, "figures": {"x": 2.5}, "tables": []}
    record = mut.measure(_section(WRITE.format(figures)))
    assert {k: record[k] for k in figures} == figures
    assert record["command"].startswith("python -c import json")
    assert record["measured_utc"].endswith("Z") and record["measured_utc"][:2] == "20"
    assert record["wall_time_s"] > 0 and record["cpu_time_s"] >= 0
    assert record["machine"]["cores"] >= 1


def test_measure_says_why_a_benchmark_failed():
    failing = "import sys; print('working'); sys.exit('error: no arena named x')"
    with pytest.raises(mut.SectionError, match="exit code 1: error: no arena named x"):
        mut.measure(_section(failing))
    with pytest.raises(mut.SectionError, match="exit code 0: no output"):
        mut.measure(_section("pass"))  # wrote no figures
    with pytest.raises(mut.SectionError, match="no tables"):
        mut.measure(_section(WRITE.format({"figures": {}})))
    with pytest.raises(mut.SectionError, match="not JSON"):
        mut.measure(_section("import sys; open(sys.argv[-1], 'w').write('{')"))


def test_measure_summarises_the_mbm_report_rows():
    rows = [{"family": "box", "valid": True, "success": True, "time_s": 0.002, "path_length": 4}]
    section = _section(WRITE.format(rows), "--limit", "7", output="--report")
    record = mut.measure(section)
    assert record["settings"] == {"limit": "7"}
    assert record["figures"]["median_ms"] == pytest.approx(2.0)
    with pytest.raises(mut.SectionError, match="rows cannot be read"):
        mut.measure(_section(WRITE.format([{"valid": True}]), output="--report"))
