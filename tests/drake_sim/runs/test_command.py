"""An app's command line from its recipe (drake_sim.runs.command): the shared flags declared
once, the scenario flag and its alias, the recipe's own flags and their groups, the overrides
and inputs they make, and one headless run from set-up to exit code. A toy app stands in for
the real ones, whose CLIs are tested as such (tests/drake_sim/test_<app>.py)."""

import dataclasses as dc
import json
from pathlib import Path

import pytest

import drake_sim.runs.command as mut
from drake_sim.base.errors import ConfigError
from drake_sim.runs import recipe


@dc.dataclass
class Robot:
    mass: float = 1.0


@dc.dataclass
class Scenario:
    mode: str = "walk"
    route: str = ""
    random_seed: int = 0


@dc.dataclass
class Report:
    end: str
    seed: int

    def to_dict(self) -> dict:
        return dc.asdict(self)


class FakeRun:
    """What ``run_app`` asks of a run; ``trouble`` is raised from ``drive``."""

    def __init__(self, inputs, options, trouble=None, error=None):
        self.inputs, self.options, self.trouble, self._error = inputs, options, trouble, error
        self.end, self.durations = "duration", []

    def default_duration(self, *, viewer=False):
        return 7.0

    def set_up_viewer(self, meshcat):
        raise AssertionError("headless: no viewer")

    def drive(self, duration, *, meshcat=None, headless=True):
        self.durations.append(duration)
        if self.trouble is not None:
            raise self.trouble

    def finish(self):
        return Report(self.end, self.inputs.seed)

    def summary(self, report):
        return f"ended by {report.end}"

    def error(self, report):
        return self._error

    def linger(self, meshcat):
        raise AssertionError("headless: nothing to linger for")


def _recipe(tmp_path, *, robot=True, **run_options):
    robot_file, scenario_file = tmp_path / "robot.yaml", tmp_path / "scenario.yaml"
    robot_file.write_text("mass: 2.0\n")
    scenario_file.write_text("mode: walk\n")
    runs = []

    def make_run(inputs, options, *, meshcat=None, realtime=False):
        assert meshcat is None and realtime is False
        runs.append(FakeRun(inputs, options, **run_options))
        return runs[-1]

    toy = recipe.AppRecipe(
        name="toy",
        robot=recipe.InputFile(Robot, lambda: robot_file, lambda r, w: r) if robot else None,
        scenario=recipe.InputFile(Scenario, lambda: scenario_file, lambda s, w: s),
        seed_key="random_seed",
        make_run=make_run,
        flags=(
            recipe.Flag("--mode", "mode", {"choices": ["walk", "run"]}),
            recipe.Flag("--route", "route", {"type": Path}, group="drive"),
            recipe.Flag("--teleop", kwargs={"action": "store_true"}, group="drive"),
            recipe.Flag("--scene", kwargs={"type": Path}, loader=True),
        ),
        cli=recipe.CliText(duration="simulated s"),
    )
    return toy, runs


def _flags(parser) -> list[str]:
    return [s for action in parser._actions for s in action.option_strings]


def test_the_shared_flags_are_there_once_with_the_recipe_s_after_them(tmp_path):
    toy, _ = _recipe(tmp_path)
    flags = _flags(mut.parser(toy, "The toy.\n\nMore."))
    for flag in (*mut.SHARED_FLAGS, "--robot", "--config", "--scenario", "--duration"):
        assert flags.count(flag) == 1, flag
    assert flags.index("--mode") < flags.index("--headless")
    assert {"--route", "--teleop", "--scene"} <= set(flags)


def test_no_robot_flag_without_a_robot_file_and_no_duration_unless_asked(tmp_path):
    toy, _ = _recipe(tmp_path, robot=False)
    toy = dc.replace(toy, cli=recipe.CliText())  # no --duration text: no --duration
    flags = _flags(mut.parser(toy, "The toy."))
    assert "--robot" not in flags and "--duration" not in flags


def test_description_prog_and_the_scenario_flag_s_alias(tmp_path):
    toy, _ = _recipe(tmp_path)
    parser = mut.parser(toy, "The toy.\n\nMore.")
    assert parser.description == "The toy." and parser.prog == "python -m drake_sim.toy"
    scenario = tmp_path / "scenario.yaml"
    assert parser.parse_args(["--config", str(scenario)]).scenario == scenario
    assert parser.parse_args(["--scenario", str(scenario)]).scenario == scenario
    pickplace_like = mut.parser(dc.replace(toy, scenario_flag="--scenario"), "The toy.")
    (action,) = [a for a in pickplace_like._actions if a.dest == "scenario"]
    assert action.option_strings == ["--scenario", "--config"]


def test_help_shows_every_flag_and_the_groups(tmp_path):
    """Two flags of one group (``--route``, ``--teleop``) make one exclusive group."""
    toy, _ = _recipe(tmp_path)
    help_text = mut.parser(toy, "The toy.").format_help()
    assert "[--route ROUTE | --teleop]" in help_text
    for flag in (*mut.SHARED_FLAGS, "--robot", "--config", "--duration", "--mode", "--scene"):
        assert flag in help_text


def test_grouped_flags_exclude_each_other_and_bad_input_is_a_config_error(tmp_path):
    toy, _ = _recipe(tmp_path)
    parser = mut.parser(toy, "The toy.")
    with pytest.raises(ConfigError, match="not allowed with argument"):
        parser.parse_args(["--route", "r.yaml", "--teleop"])
    with pytest.raises(ConfigError, match="invalid choice"):
        parser.parse_args(["--mode", "fly"])
    with pytest.raises(ConfigError, match="scenario file not found"):
        parser.parse_args(["--config", str(tmp_path / "missing.yaml")])


def test_overrides_are_set_first_then_the_flags(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    toy, _ = _recipe(tmp_path)
    args = mut.parser(toy, "The toy.").parse_args(
        ["--mode", "run", "--set", "mode=walk", "--route", "r.yaml", "--set", "robot.mass=3"]
    )
    assert mut.overrides_from_args(toy, args) == [
        "mode=walk",
        "robot.mass=3",
        ("--mode run", 'mode="run"'),
        ("--route r.yaml", f'route="{tmp_path / "r.yaml"}"'),
    ]
    inputs = mut.load_from_args(toy, args)
    assert inputs.scenario.mode == "run" and inputs.robot.mass == 3.0  # the flag wins


def test_load_from_args_applies_the_seed_and_gives_loader_flags_to_the_loader(tmp_path):
    toy, _ = _recipe(tmp_path)
    calls = []

    def load_overridden(path, overrides, **loader):
        calls.append(loader)
        return Scenario(random_seed=int(overrides[-1].split("=")[1]))

    toy = dc.replace(toy, scenario=dc.replace(toy.scenario, load_overridden=load_overridden))
    args = mut.parser(toy, "The toy.").parse_args(["--seed", "4", "--scene", "s.yaml"])
    assert mut.load_from_args(toy, args).seed == 4
    assert calls == [{"scene": Path("s.yaml")}]


def test_teleop_needs_the_viewer(tmp_path):
    toy, runs = _recipe(tmp_path)
    args = mut.parser(toy, "The toy.").parse_args(["--teleop", "--headless"])
    with pytest.raises(ConfigError, match="--teleop needs the viewer"):
        mut.run_app(toy, args)
    assert runs == []


def test_a_headless_run_prints_its_summary_and_writes_its_report(tmp_path, capsys):
    toy, runs = _recipe(tmp_path)
    report_file = tmp_path / "report.json"
    args = mut.parser(toy, "The toy.").parse_args(
        ["--headless", "--seed", "2", "--report", str(report_file)]
    )
    assert mut.run_app(toy, args) == 0
    (run,) = runs
    assert run.options is args and run.durations == [7.0]  # the run's default duration
    assert capsys.readouterr().out == "ended by duration\n"
    assert json.loads(report_file.read_text()) == {"end": "duration", "seed": 2}


def test_a_failed_run_exits_1_with_one_error_line(tmp_path, capsys):
    toy, runs = _recipe(tmp_path, error="the robot fell")
    args = mut.parser(toy, "The toy.").parse_args(["--headless", "--duration", "3"])
    assert mut.run_app(toy, args) == 1
    assert runs[0].durations == [3.0]
    assert capsys.readouterr().err == "error: the robot fell\n"


def test_a_stop_the_run_did_not_catch_ends_it_as_stopped(tmp_path, capsys):
    toy, runs = _recipe(tmp_path, trouble=KeyboardInterrupt())
    args = mut.parser(toy, "The toy.").parse_args(["--headless"])
    assert mut.run_app(toy, args) == 0
    assert runs[0].end == "stopped" and capsys.readouterr().out == "ended by stopped\n"


def test_other_errors_are_raised(tmp_path):
    toy, _ = _recipe(tmp_path, trouble=ValueError("a bug"))
    args = mut.parser(toy, "The toy.").parse_args(["--headless"])
    with pytest.raises(ValueError, match="a bug"):
        mut.run_app(toy, args)
