"""drake_sim.tools.architecture: the import graph of the project, its rooms, and the picture."""

import shutil

import pytest

import drake_sim.tools.architecture as mut


def test_the_graph_holds_every_module_and_reads_imports_in_functions():
    graph = mut.import_graph()
    assert "drake_sim.runs.recipe" in graph and "planning.model.panda" in graph
    assert "drake_sim.base.config" in graph["drake_sim.runs.recipe"]
    # drake_sim.tools.architecture imports drake_sim.base.cli at the top; flip imports diagrams.
    assert "drake_sim.base.cli" in graph["drake_sim.tools.architecture"]
    assert "diagrams.flip" in graph["drake_sim.runs.flip"]


def test_room_graph():
    graph = {"a.b.c": {"a.d.e", "a.b.f"}, "a.b.f": set(), "a.d.e": {"x.y"}}
    assert mut.room_graph(graph) == {"a.b": {"a.d"}, "a.d": {"x.y"}}
    assert mut.room_of("planning.model.panda") == "planning.model"


def test_dot_source_keeps_only_the_arrows_no_longer_path_implies():
    rooms = {"drake_sim.c": {"drake_sim.b", "drake_sim.a"}, "drake_sim.b": {"drake_sim.a"}}
    rooms["drake_sim.a"] = set()
    source = mut.dot_source(rooms)
    assert '"drake_sim.c" -> "drake_sim.b";' in source
    assert '"drake_sim.b" -> "drake_sim.a";' in source
    assert '"drake_sim.c" -> "drake_sim.a";' not in source  # implied by c -> b -> a


def test_main_prints_the_source(capsys):
    assert mut.main(["--dot"]) == 0
    assert capsys.readouterr().out.startswith("digraph architecture {")


@pytest.mark.skipif(shutil.which("dot") is None, reason="Graphviz's dot is not installed")
def test_main_writes_the_picture(tmp_path):
    out = tmp_path / "a.svg"
    assert mut.main(["--out", str(out)]) == 0
    assert "<svg" in out.read_text() and "drake_sim.runs" in out.read_text()
