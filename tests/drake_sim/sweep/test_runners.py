import pytest

from drake_sim.base import config
from drake_sim.base.errors import ConfigError
from drake_sim.robots.ddrive import default_robot_file
from drake_sim.sweep import jobs
from drake_sim.sweep import runners as mut
from drake_sim.sweep.spec import load_sweep
from tests.drake_sim.runs.test_explore import SMALL_ROOM
from tests.drake_sim.sweep.sweep_files import tiny_flip, write_sweep
from tests.drake_sim.sweep.test_jobs import Inner, Outer


def test_override_strings():
    overrides = {"rate": 5, "inner.position[0]": 9.5, "inner.position[2]": -1.0, "m": "physics"}
    dut = mut.override_strings(overrides)
    assert dut == ["rate=5", "inner.position[0]=9.5", "inner.position[2]=-1.0", 'm="physics"']
    overridden = config.apply_overrides(Outer, Outer(), dut[:3])
    assert overridden == Outer(rate=5.0, inner=Inner(position=[9.5, 2.0, -1.0]))


def job_of(tmp_path, text):
    return jobs.make_job(load_sweep(write_sweep(tmp_path, text)))


def test_make_job(tmp_path):
    job = jobs.make_job(load_sweep(tiny_flip(tmp_path)))
    assert job["runner"] == "flip"
    assert job["scenario"].endswith("config/flip.yaml")
    assert job["options"] == {"duration": 0.3, "robot": None}


def test_make_job_resolves_the_robot_file_next_to_the_sweep(tmp_path):
    (tmp_path / "robots").mkdir()
    (tmp_path / "robots" / "r.yaml").write_text(default_robot_file().read_text())
    job = job_of(tmp_path, "runner: flip\noptions: {robot: robots/r.yaml}\n")
    assert job["options"]["robot"] == str((tmp_path / "robots" / "r.yaml").resolve())
    with pytest.raises(ConfigError, match="no such robot file"):
        job_of(tmp_path, "runner: flip\noptions: {robot: robots/none.yaml}\n")


@pytest.mark.parametrize(
    "text, needle",
    [
        (
            "runner: rocket\n",
            "unknown runner 'rocket' (known: flip, pickplace, walle, navigation, explore)",
        ),
        ("runner: flip\noptions: {speed: 1}\n", "unknown option 'speed' for flip"),
        (
            "runner: flip\nparameters: {flip.drive_sped: {grid: [1]}}\n",
            "unknown parameter path 'flip.drive_sped'",
        ),
        (
            "runner: flip\nparameters: {robot.body.weight: {grid: [1]}}\n",
            "unknown parameter path 'body.weight'",
        ),
        (
            "runner: pickplace\nparameters: {'scene.object.position[5]': {grid: [1]}}\n",
            "scene.object.position has no item 5",
        ),
        ("runner: flip\nmetrics: [flipz]\n", "'flipz' is not a flip report key"),
        ("runner: pickplace\nsuccess: won\n", "'won' is not a pickplace report key"),
    ],
)
def test_make_job_bad_input(tmp_path, text, needle):
    with pytest.raises(ConfigError, match="sweep.yaml") as info:
        job_of(tmp_path, text)
    assert needle in str(info.value)


def test_run_rollout_flip(tmp_path):
    job = jobs.make_job(load_sweep(tiny_flip(tmp_path, duration=0.2)))
    rollout = {"index": 4, "seed": 11, "overrides": {"flip.drive_speed": 0.7}}
    dut = mut.run_rollout(job, rollout)
    assert (dut["index"], dut["seed"], dut["status"], dut["reason"]) == (4, 11, "ok", "")
    assert dut["report"]["sim_time_s"] == pytest.approx(0.2)
    assert dut["report"]["seed"] == 11
    assert dut["wall_time_s"] > 0 and ":" in dut["worker"]


def test_a_failing_rollout_is_a_row_with_its_reason(tmp_path):
    job = jobs.make_job(load_sweep(tiny_flip(tmp_path, duration=0.2)))
    dut = mut.run_rollout(job, {"index": 0, "seed": 1, "overrides": {"robot.body.mass": -1.0}})
    assert dut["status"] == "failed"
    assert dut["reason"].startswith("ConfigError: ")
    assert "'body.mass' must be finite and > 0" in dut["reason"]
    assert dut["report"] == {}


def test_pickplace_rollout_moves_the_object(tmp_path):
    job = job_of(tmp_path, "runner: pickplace\n")
    runner = mut.get_runner("pickplace")
    default = runner.load(job["scenario"], {}, {}, 5).scenario
    overrides = {
        "scene.object.position[1]": -0.3,
        "mode": "kinematic",
        "scene.object.position[0]": 0.55,
    }
    moved = runner.load(job["scenario"], {}, overrides, 5).scenario
    assert moved.scene.object.position == [0.55, -0.3, default.scene.object.position[2]]
    assert moved.mode == "kinematic"
    assert moved.planner.seed == 5


def test_walle_rollout(tmp_path):
    text = (
        "runner: walle\noptions: {duration: 0.3}\n"
        "parameters: {robot.body.mass: {grid: [1.0]}, mode: {grid: [balance]}}\n"
        "metrics: [fell, max_abs_pitch_deg]\n"
    )
    job = job_of(tmp_path, text)
    rollout = {"index": 0, "seed": 2, "overrides": {"robot.body.mass": 1.0, "mode": "balance"}}
    dut = mut.run_rollout(job, rollout)
    assert dut["status"] == "ok", dut["reason"]
    assert dut["report"]["mode"] == "balance" and dut["report"]["fell"] is False
    assert dut["report"]["sim_time_s"] == pytest.approx(0.3, abs=0.05)
    with pytest.raises(ConfigError, match="unknown parameter path 'body.masss'"):
        job_of(tmp_path, "runner: walle\nparameters: {robot.body.masss: {grid: [1]}}\n")


def test_navigation_runner_checks_its_paths_and_drives_to_a_goal(tmp_path):
    job = job_of(
        tmp_path,
        "runner: navigation\noptions: {goals: 1}\n"
        "parameters: {lidar.noise_sigma: {grid: [0.01]}, robot.limits.max_linear_velocity:"
        " {grid: [0.2]}}\nmetrics: [goals_reached, max_position_error_m, collisions]\n",
    )
    assert job["options"]["goals"] == 1 and job["options"]["map"] is None
    with pytest.raises(ConfigError, match="unknown parameter path 'lidar.bogus'"):
        job_of(tmp_path, "runner: navigation\nparameters: {lidar.bogus: {grid: [1]}}\n")
    with pytest.raises(ConfigError, match="'goals' is not a navigation report key"):
        job_of(tmp_path, "runner: navigation\nmetrics: [goals]\n")
    row = mut.run_rollout(job, {"index": 0, "seed": 4, "overrides": {"lidar.noise_sigma": 0.01}})
    assert row["status"] == "ok", row["reason"]
    report = row["report"]
    assert report["goals_reached"] == 1 and report["reached_all"] and report["collisions"] == 0
    assert report["max_position_error_m"] <= 0.05


def test_explore_runner_explores_an_arena_of_the_sweep(tmp_path):
    arena = tmp_path / "small.yaml"
    arena.write_text(SMALL_ROOM)
    job = job_of(
        tmp_path,
        f"runner: explore\nparameters: {{arena: {{grid: [{arena}]}}}}\n"
        "metrics: [known_fraction, map_iou, frontiers_visited]\n",
    )
    with pytest.raises(ConfigError, match="unknown parameter path 'exploration.bogus'"):
        job_of(tmp_path, "runner: explore\nparameters: {exploration.bogus: {grid: [1]}}\n")
    row = mut.run_rollout(job, {"index": 0, "seed": 1, "overrides": {"arena": str(arena)}})
    assert row["status"] == "ok", row["reason"]
    report = row["report"]
    assert report["end"] == "explored" and report["known_fraction"] >= 0.95
    assert report["collisions"] == 0 and report["map_files"] is None


def test_random_scenes_are_generated_by_number(tmp_path):
    with pytest.raises(ConfigError, match="flip generates nothing"):
        job_of(tmp_path, "runner: flip\nparameters: {flip: {random: 2}}\n")
    with pytest.raises(ConfigError, match="'scene.object.mass' is inside a generated value"):
        job_of(
            tmp_path,
            "runner: pickplace\nparameters: {scene: {random: 2},"
            " scene.object.mass: {uniform: [0.1, 0.2]}}\n",
        )
    job = job_of(tmp_path, "runner: pickplace\nparameters: {scene: {random: 2}}\n")
    runner = mut.get_runner("pickplace")
    scenes = [
        runner.load(job["scenario"], {}, {"scene": k}, seed=1).scenario.scene for k in (0, 1, 0)
    ]
    assert scenes[0] == scenes[2] and scenes[0] != scenes[1]  # scene k is always the same
    default = runner.load(job["scenario"], {}, {}, seed=1).scenario.scene
    assert scenes[0].object != default.object
