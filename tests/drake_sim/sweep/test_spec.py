import math

import pytest

from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from drake_sim.sweep import spec as mut
from tests.drake_sim.sweep.sweep_files import tiny_flip, write_sweep

BASE = "runner: flip\n"


def load_text(tmp_path, text):
    return mut.load_sweep(write_sweep(tmp_path, text))


def test_shipped_sweeps_parse():
    sizes = {}
    for path in sorted((config_dir() / "sweeps").glob("*.yaml")):
        sizes[path.stem] = mut.load_sweep(path).size
    assert sizes == {
        "explore_arenas": 6,
        "flip_imu_noise": 25,
        "flip_robot_variants": 60,
        "navigation_lidar_noise": 15,
        "pickplace_random_scenes": 400,
    }


def test_fields(tmp_path):
    dut = mut.load_sweep(tiny_flip(tmp_path, repeats=3))
    assert (dut.name, dut.runner, dut.seed, dut.repeats, dut.samples) == ("tiny", "flip", 3, 3, 1)
    assert dut.parameters == (mut.Parameter("flip.drive_speed", "grid", (0.6, 0.8)),)
    assert dut.metrics == ("flips", "travel_extent_m", "odometry_error_m")
    assert dut.options == {"duration": 0.3}
    assert dut.size == 6


def test_paths_are_set_keys_with_list_indices(tmp_path):
    """Parameter paths are read like ``--set`` keys (``config.parse_key_path``)."""
    text = BASE + "parameters: {'m[1][0]': {grid: [1]}, 'pushes[0].force[2]': {grid: [2]}}\n"
    dut = load_text(tmp_path, text)
    assert [p.path for p in dut.parameters] == ["m[1][0]", "pushes[0].force[2]"]


def test_scenario_is_relative_to_the_sweep_file(tmp_path):
    dut = load_text(tmp_path, BASE + "scenario: sub/flip.yaml\n")
    assert dut.scenario == str((tmp_path / "sub" / "flip.yaml").resolve())


@pytest.mark.parametrize(
    "text, needle",
    [
        ("runner: flip\nbogus: 1\n", "unknown key 'bogus'"),
        ("seed: 1\n", "'runner' must name a runner"),
        (BASE + "parameters: {a.b: {grid: []}}\n", "grid needs a non-empty list"),
        (BASE + "parameters: {a.b: {uniform: [3, 1]}}\n", "needs low < high"),
        (BASE + "parameters: {a.b: {uniform: [1]}}\n", "two numbers [low, high]"),
        (BASE + "parameters: {a.b: {normal: [0, -1]}}\n", "needs sigma >= 0"),
        (BASE + "parameters: {a.b: {uniform: [0, .nan]}}\n", "must be finite"),
        (BASE + "parameters: {a.b: {grid: [1, .inf]}}\n", "must be finite"),
        (BASE + "parameters: {a.b: {grid: [1, 'nan']}}\n", "must be a finite number"),
        (BASE + "parameters: {a.b: {gaussian: [0, 1]}}\n", "unknown distribution 'gaussian'"),
        (BASE + "parameters: {a.b: {grid: [1], uniform: [0, 1]}}\n", "must be one of"),
        (BASE + "parameters: {'a..b': {grid: [1]}}\n", "not a dotted path"),
        (BASE + "parameters: {'a[-1]': {grid: [1]}}\n", "negative index [-1]"),
        (BASE + "parameters: {'a[0': {grid: [1]}}\n", "brackets out of place in 'a[0'"),
        (BASE + "parameters: {'a=b': {grid: [1]}}\n", "'=' in 'a=b'"),
        (BASE + "parameters: {3: {grid: [1]}}\n", "not a dotted path"),
        (BASE + "repeats: 0\n", "'repeats' must be an integer >= 1"),
        (BASE + "samples: 1.5\n", "'samples' must be an integer >= 1"),
        (BASE + "metrics: flips\n", "'metrics' must be a list"),
        (BASE + "metrics: [flips, flips]\n", "lists a key twice"),
        (BASE + "metrics: [success]\n", "metric 'success' is already a column"),
        (BASE + "metrics: [wall_time_s]\n", "metric 'wall_time_s' is already a column"),
        (BASE + "success: 'flips >>= 2'\n", "is not KEY or KEY OP VALUE"),
        (BASE + "name: 'a b'\n", "'name' must be"),
        ("- runner\n", "expected a mapping"),
    ],
)
def test_bad_input(tmp_path, text, needle):
    with pytest.raises(ConfigError, match="sweep.yaml") as info:
        load_text(tmp_path, text)
    assert needle in str(info.value)


def test_success_conditions(tmp_path):
    dut = load_text(tmp_path, BASE + "success: [flips >= 2, 'stuck == false', finite]\n")
    assert dut.success[0] == mut.Condition("flips", ">=", 2)
    assert dut.success[1] == mut.Condition("stuck", "==", False)
    assert dut.success[2] == mut.Condition("finite")
    good = {"flips": 3, "stuck": False, "finite": True}
    assert all(c.holds(good) for c in dut.success)
    assert not dut.success[0].holds({"flips": 1})
    assert not dut.success[0].holds({})  # a missing key never succeeds
    assert not dut.success[2].holds({"finite": False})


RANDOM = """\
runner: pickplace
seed: 7
samples: 4
repeats: 2
parameters:
  mode: {grid: [kinematic, physics]}
  scene.object.position[0]: {uniform: [0.4, 0.6]}
  task.lift_height: {normal: [0.1, 0.01]}
  planner.timeout: {choice: [1.0, 2.0]}
"""


def test_rollouts_are_deterministic_and_ordered(tmp_path):
    spec = load_text(tmp_path, RANDOM)
    dut = mut.rollouts(spec)
    assert dut == mut.rollouts(load_text(tmp_path, RANDOM))  # same file, same list
    assert len(dut) == spec.size == 2 * 4 * 2
    assert [r.index for r in dut] == list(range(16))
    assert [r.overrides["mode"] for r in dut] == ["kinematic"] * 8 + ["physics"] * 8
    assert list(dut[0].overrides) == [p.path for p in spec.parameters]
    for first, second in zip(dut[::2], dut[1::2], strict=True):  # repeats share the draw
        assert first.overrides == second.overrides and first.seed != second.seed
    draws = [r.overrides["scene.object.position[0]"] for r in dut[::2]]
    assert len(set(draws)) == 4 and all(0.4 <= x < 0.6 for x in draws)
    assert {r.overrides["planner.timeout"] for r in dut} <= {1.0, 2.0}
    assert len({r.seed for r in dut[:8]}) == 8
    assert all(0 <= r.seed < 2**31 for r in dut)


def test_grid_points_share_draws_and_seeds(tmp_path):
    """Common random numbers: kinematic and physics run on the same scenes with the same seeds."""
    dut = mut.rollouts(load_text(tmp_path, RANDOM))
    kinematic, physics = dut[:8], dut[8:]
    assert [r.seed for r in kinematic] == [r.seed for r in physics]
    for a, b in zip(kinematic, physics, strict=True):
        assert {**a.overrides, "mode": None} == {**b.overrides, "mode": None}


def test_rollouts_change_with_the_seed(tmp_path):
    a = mut.rollouts(load_text(tmp_path, RANDOM))
    b = mut.rollouts(load_text(tmp_path, RANDOM.replace("seed: 7", "seed: 8")))
    assert [r.seed for r in a] != [r.seed for r in b]
    assert a[0].overrides != b[0].overrides


def test_a_prefix_of_the_list_does_not_depend_on_its_length(tmp_path):
    """--limit and --resume rely on rollout i being the same whatever else is in the sweep."""
    small = mut.rollouts(load_text(tmp_path, RANDOM))
    big = mut.rollouts(load_text(tmp_path, RANDOM.replace("samples: 4", "samples: 9")))
    assert small[:8] == big[:8]  # the kinematic draws 0-3 of both


def test_no_parameters_is_one_rollout_per_repeat(tmp_path):
    dut = mut.rollouts(load_text(tmp_path, BASE + "repeats: 3\n"))
    assert [r.overrides for r in dut] == [{}, {}, {}]
    assert not math.isnan(dut[0].seed)


def test_random_counts_generated_values(tmp_path):
    path = write_sweep(
        tmp_path,
        "runner: pickplace\nparameters: {mode: {grid: [kinematic, physics]}, scene: {random: 3}}\n",
    )
    dut = mut.load_sweep(path)
    assert dut.size == 6
    assert [r.overrides for r in mut.rollouts(dut)[:4]] == [
        {"mode": "kinematic", "scene": 0},
        {"mode": "kinematic", "scene": 1},
        {"mode": "kinematic", "scene": 2},
        {"mode": "physics", "scene": 0},
    ]
    for bad in ("0", "-2", "[3]", "2.5", "true"):
        with pytest.raises(ConfigError, match="random needs a count >= 1"):
            mut.load_sweep(
                write_sweep(
                    tmp_path, f"runner: pickplace\nparameters: {{scene: {{random: {bad}}}}}\n"
                )
            )
