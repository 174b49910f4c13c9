"""drake_sim.base.cli: usage errors are ConfigErrors, ``run`` turns bad input into one stderr
line and exit code 2 (Ctrl-C into 0), the argparse types reject bad text, and ``write_replay``
writes Meshcat's scene as HTML."""

import argparse
from pathlib import Path

import pytest
from pydrake.geometry import Meshcat, Rgba, Sphere

import drake_sim.base.cli as mut
from drake_sim.base.errors import ConfigError
from tests.meshcat_html import scene_paths


def _parser() -> mut.ArgumentParser:
    dut = mut.ArgumentParser(prog="tool")
    dut.add_argument("--rate", type=mut.positive_float, default=1.0)
    dut.add_argument("--seed", type=mut.non_negative_int, default=0)
    dut.add_argument("--count", type=mut.positive_int, default=1)
    return dut


def test_parser_errors_are_config_errors():
    dut = _parser()
    assert dut.parse_args(["--rate", "2.5", "--seed", "0", "--count", "3"]) == argparse.Namespace(
        rate=2.5, seed=0, count=3
    )
    with pytest.raises(
        ConfigError, match=r"^tool: unrecognized arguments: --bogus \(see --help\)$"
    ):
        dut.parse_args(["--bogus"])
    with pytest.raises(ConfigError, match=r"tool: argument --rate: must be a finite number > 0"):
        dut.parse_args(["--rate", "-1"])
    with pytest.raises(ConfigError, match=r"argument --count: must be >= 1, got 0"):
        dut.parse_args(["--count", "0"])


@pytest.mark.parametrize("text", ["0", "-1", "inf", "nan", "-inf", "abc", ""])
def test_positive_float_rejects(text):
    with pytest.raises(argparse.ArgumentTypeError, match=repr(text)):
        mut.positive_float(text)


def test_positive_float_accepts():
    assert mut.positive_float("2.5") == 2.5
    assert mut.positive_float("1e-3") == 1e-3


@pytest.mark.parametrize(
    "func, text, match",
    [
        (mut.non_negative_int, "-1", "must be >= 0, got -1"),
        (mut.non_negative_int, "1.5", "not an integer: '1.5'"),
        (mut.non_negative_int, "x", "not an integer: 'x'"),
        (mut.positive_int, "0", "must be >= 1, got 0"),
        (mut.positive_int, "", "not an integer: ''"),
    ],
)
def test_integer_types_reject(func, text, match):
    with pytest.raises(argparse.ArgumentTypeError, match=match):
        func(text)


def test_integer_types_accept():
    assert mut.non_negative_int("0") == 0 and mut.non_negative_int("7") == 7
    assert mut.positive_int("1") == 1 and mut.positive_int(" 12 ") == 12


def test_run_returns_main_code_and_passes_argv():
    seen = []

    def main(argv):
        seen.append(argv)
        return 1

    assert mut.run(main, ["--x"]) == mut.EXIT_FAILED
    assert seen == [["--x"]]


def test_run_turns_config_error_into_one_line_and_exit_2(capsys):
    def main(argv):
        raise ConfigError("f.yaml: 'rate'\n   must be > 0")

    assert mut.run(main, []) == mut.EXIT_BAD_INPUT == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err == "error: f.yaml: 'rate' must be > 0\n"


def test_run_usage_error_is_bad_input(capsys):
    assert mut.run(lambda argv: _parser().parse_args(argv) and 0, ["--seed", "-3"]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: tool: argument --seed: must be >= 0")


def test_run_ends_quietly_on_ctrl_c(capsys):
    def main(argv):
        raise KeyboardInterrupt

    assert mut.run(main) == mut.EXIT_OK == 0
    assert capsys.readouterr() == ("", "")


def test_run_lets_bugs_through():
    def main(argv):
        raise RuntimeError("a bug, not bad input")

    with pytest.raises(RuntimeError):
        mut.run(main)


def test_robot_and_config_options(tmp_path):
    dut = mut.ArgumentParser(prog="tool")
    mut.add_robot_and_config_options(
        dut, default_robot=tmp_path / "r.yaml", default_config=tmp_path / "c.yaml"
    )
    args = dut.parse_args([])
    assert (args.robot, args.config) == (tmp_path / "r.yaml", tmp_path / "c.yaml")
    args = dut.parse_args(["--robot", "a.yaml", "--config", "b.yaml"])
    assert (args.robot, args.config) == (Path("a.yaml"), Path("b.yaml"))


@pytest.fixture(scope="module")
def meshcat():
    return Meshcat()


def test_write_replay_writes_html(meshcat, tmp_path, capsys):
    meshcat.StartRecording()
    meshcat.SetObject("ball", Sphere(0.1), Rgba(1, 0, 0, 1))
    path = tmp_path / "out" / "replay.html"  # the folder is created
    mut.write_replay(meshcat, path)
    html = path.read_text()
    assert html.lstrip().lower().startswith("<!doctype html")
    assert "/drake/ball" in scene_paths(html)
    assert capsys.readouterr().out == f"wrote {path}\n"


def test_write_replay_without_recording(meshcat, tmp_path):
    meshcat.SetObject("cube", Sphere(0.2), Rgba(0, 1, 0, 1))
    path = tmp_path / "scene.html"
    mut.write_replay(meshcat, path, recording=False)
    assert "/drake/cube" in scene_paths(path.read_text())
