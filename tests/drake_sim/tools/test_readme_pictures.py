"""``python -m drake_sim.tools.readme_pictures``: diagrams, the GIF hook and the missing-tool
errors."""

import shutil
from pathlib import Path

import pytest

import drake_sim.tools.readme_pictures as mut
from drake_sim.base.errors import ConfigError
from tests.browser_helpers import require_chromium

SMALL_DOT = "digraph { a -> b }"


def _require_dot():
    if shutil.which("dot") is None:
        pytest.skip("Graphviz's dot not found (apt-get install graphviz)")


def test_missing_dot_is_a_clear_error(monkeypatch, tmp_path):
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(ConfigError, match="apt-get install graphviz"):
        mut.need_dot()
    with pytest.raises(ConfigError, match="`dot` not found"):
        mut.main(["--out", str(tmp_path), "--only", "diagrams"])


def test_diagram_sources_name_their_systems():
    flip_source = mut.flip_diagram_graphviz()
    for name in ("flip_controller", "odometry", "plant", "scene_graph"):
        assert f"name={name}" in flip_source
    assert "traffic_cone" not in flip_source  # Drawn on bare ground.
    station_source = mut.panda_station_graphviz()
    assert "panda_station_physics" in station_source
    assert "panda.position_command" in station_source


def test_render_graphviz_writes_svg_and_png(tmp_path):
    _require_dot()
    svg = mut.render_graphviz(SMALL_DOT, tmp_path / "d" / "g.svg")
    assert "<svg" in svg.read_text()
    png = mut.render_graphviz(SMALL_DOT, tmp_path / "g.png")
    assert png.read_bytes().startswith(b"\x89PNG")
    with pytest.raises(RuntimeError, match="dot failed"):
        mut.render_graphviz("digraph {", tmp_path / "bad.svg")


def test_make_diagrams(tmp_path):
    _require_dot()
    paths = mut.make_diagrams(tmp_path)
    assert [p.name for p in paths] == ["flip_diagram.svg", "panda_station_diagram.svg"]
    assert all("<svg" in p.read_text() for p in paths)


def test_pickplace_hook_waits_for_its_module(monkeypatch, tmp_path, capsys):
    spec = mut.GifSpec("drake_sim.no_such_module")
    monkeypatch.setattr(mut, "PICKPLACE_GIF", spec)
    assert mut.make_pickplace_gif(tmp_path) == []
    assert "does not exist yet" in capsys.readouterr().out
    assert set(mut.PICTURES) == {"flip", "diagrams", "pickplace", "walle", "mapping", "navigation"}


def test_record_replay_reports_a_failed_run(tmp_path):
    with pytest.raises(RuntimeError, match="exit 2"):
        mut.record_replay("drake_sim.flip", tmp_path / "x.html", ["--duration", "-1"])


@pytest.mark.browser
def test_replay_gif(tmp_path):
    require_chromium()
    bare = tmp_path / "bare.yaml"
    bare.write_text("scene: {world: ''}\n")
    args = ("--duration", "1", "--config", str(bare))
    spec = mut.GifSpec("drake_sim.flip", args, frames=3, size=(160, 100))
    out = mut.replay_gif(spec, tmp_path / "flip.gif")
    assert out.read_bytes().startswith(b"GIF89a")


def test_the_mapping_gif_records_the_room_from_above():
    spec = mut.MAPPING_GIF
    assert spec.module == "drake_sim.mapping"
    arena = spec.args[spec.args.index("--arena") + 1]
    assert arena.endswith("room.yaml") and Path(arena).is_file()
    assert spec.camera is not None and spec.camera[2] > 5.0  # well above the 6 x 5 m room
