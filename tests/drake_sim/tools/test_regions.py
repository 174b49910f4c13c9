"""``python -m drake_sim.tools.regions``: --help, bad input (exit 2, one stderr line), the seeds it
grows regions for and its summary (region growing replaced by a fake: test_gcs grows real ones), and
``pick_place_seeds``."""

import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest
from pydrake.math import RigidTransform

import drake_sim.tools.regions as mut
import planning
import planning.search.iris_regions as iris_regions
from drake_sim.base.cli import run
from tests.cli_helpers import assert_bad_input

SCENE = """
table:    {size: [1.2, 1.4, 0.04], position: [0.3, 0.0, -0.02]}
object:   {size: [0.045, 0.045, 0.08], position: [0.5, -0.25, 0.04], mass: 0.1}
obstacle: {size: [0.3, 0.04, 0.2], position: [0.5, 0.0, 0.1]}
place:    {position: [0.5, 0.25, 0.04]}
"""


@pytest.fixture(scope="module")
def shared_scene():
    return planning.PlanningScene()


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_text(SCENE)
    return path


@pytest.fixture
def cli(shared_scene, monkeypatch, capsys):
    """Runs main in-process as ``python -m`` would; returns (exit code, stdout, stderr). Every
    run gets the one shared PlanningScene (building one per run is slow)."""
    monkeypatch.setattr(planning, "PlanningScene", lambda: shared_scene)

    def call(*args):
        code = run(mut.main, [str(a) for a in args])
        out, err = capsys.readouterr()
        return code, out, err

    return call


@pytest.fixture
def grown(monkeypatch):
    """Replaces region growing by a fake that records its seeds and options."""
    calls = []

    def fake(scene, seeds, options, *, progress=None):
        calls.append(SimpleNamespace(seeds=np.array(seeds), options=options))
        progress("region 1: fake")
        return iris_regions.RegionSet(["A", "B"], np.array(seeds), "key", "cache/key.npz")

    monkeypatch.setattr(iris_regions, "load_or_build_regions", fake)
    return calls


def test_help_exits_0():
    result = subprocess.run(
        [sys.executable, "-m", "drake_sim.tools.regions", "--help"], capture_output=True, text=True
    )
    assert result.returncode == 0 and result.stderr == ""
    assert result.stdout.startswith("usage: python -m drake_sim.tools.regions")
    for option in ("--scene", "--named", "--no-pick-place", "--seeds", "--options", "--set"):
        assert option in result.stdout


def test_missing_scene_exits_2_with_one_stderr_line(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "drake_sim.tools.regions", "--scene", str(tmp_path / "none.yaml")],
        capture_output=True,
        text=True,
    )
    assert_bad_input(result, "none.yaml")


@pytest.mark.parametrize(
    "args, needle",
    [
        ([], "--scene"),
        (["--approach-height", "-1"], "approach-height"),
        (["--set", "bogus=1"], "bogus"),
        (["--set", "epsilon"], "epsilon"),
        (["--set", "epsilon=x"], "epsilon"),
        (["--set", "epsilon=2.0"], "epsilon"),
        (["--named", "dance"], "dance"),
        (["--named", "--no-pick-place"], "no seeds"),
    ],
)
def test_bad_input_exits_2_with_one_stderr_line(cli, grown, scene_file, args, needle):
    scene = [] if args == [] else ["--scene", scene_file]
    code, out, err = cli(*scene, *args)
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and needle in err and err.startswith("error: ")
    assert grown == []  # nothing was grown


def test_bad_files_exit_2_naming_them(cli, grown, scene_file, tmp_path):
    bad_scene = tmp_path / "bad_scene.yaml"
    bad_scene.write_text("tabel: {size: [1, 1, 1]}\n")
    bad_options = tmp_path / "options.yaml"
    bad_options.write_text("num_particles: lots\n")
    bad_seeds = tmp_path / "seeds.yaml"
    bad_seeds.write_text("[[0, 1, 2]]\n")
    for args, needle in [
        (["--scene", bad_scene], "bad_scene.yaml"),
        (["--scene", scene_file, "--options", bad_options], "options.yaml"),
        (["--scene", scene_file, "--options", tmp_path / "none.yaml"], "none.yaml"),
        (["--scene", scene_file, "--seeds", bad_seeds], "seeds.yaml"),
    ]:
        code, _, err = cli(*args)
        assert code == 2 and len(err.strip().splitlines()) == 1 and needle in err, err
    assert grown == []


def test_seeds_in_route_order_and_the_summary(cli, grown, scene_file, shared_scene, tmp_path):
    seeds_file = tmp_path / "seeds.yaml"
    seeds_file.write_text("[[0, -0.5, 0, -2.0, 0, 1.5, 0.7]]\n")
    code, out, err = cli(
        "--scene", scene_file, "--named", "ready", "extended", "--seeds", seeds_file,
        "--set", "num_particles=200", "--set", "epsilon=0.05",
    )  # fmt: skip
    assert code == 0, err
    (call,) = grown
    state = planning.RobotState(shared_scene)
    assert len(call.seeds) == 5  # ready, extended, pre-grasp, pre-place, the file's
    np.testing.assert_allclose(call.seeds[0], state.named("ready"))
    np.testing.assert_allclose(call.seeds[1], state.named("extended"))
    expected = mut.pick_place_seeds(shared_scene, state, 0.12)
    np.testing.assert_allclose(call.seeds[2:4], expected)
    np.testing.assert_allclose(call.seeds[4], [0, -0.5, 0, -2.0, 0, 1.5, 0.7])
    assert call.options.num_particles == 200 and call.options.epsilon == 0.05
    assert out.startswith("2 regions for 5 seeds built and saved to cache/key.npz")
    assert "region 1: fake" in err  # progress


def test_failure_to_grow_exits_1(cli, scene_file, monkeypatch):
    def fail(*args, **kwargs):
        raise RuntimeError("no path joins seeds 0 and 1")

    monkeypatch.setattr(iris_regions, "load_or_build_regions", fail)
    code, _, err = cli("--scene", scene_file, "--no-pick-place")
    assert code == 1 and "failed: no path joins seeds 0 and 1" in err


def test_pick_place_seeds_point_the_hand_down_above_object_and_place(shared_scene, scene_file):
    shared_scene.load_yaml(scene_file)
    state = planning.RobotState(shared_scene)
    seeds = mut.pick_place_seeds(shared_scene, state, height=0.1)
    targets = [shared_scene.object_pose("object").translation(), shared_scene.place_position]
    assert len(seeds) == 2
    for q, p in zip(seeds, targets, strict=True):
        X_WE = state.fk(q)
        np.testing.assert_allclose(X_WE.translation(), p + [0, 0, 0.1], atol=1.1e-3)
        np.testing.assert_allclose(X_WE.rotation().col(2), [0, 0, -1], atol=0.011)
        assert shared_scene.is_collision_free(q)
    shared_scene.clear()
    shared_scene.place_position = None
    shared_scene.add_box("table", [1.2, 1.4, 0.04], RigidTransform([0.3, 0.0, -0.02]))
    assert mut.pick_place_seeds(shared_scene, state, height=0.1) == []
