"""MotionPlannerOptions: documented defaults, nested YAML, range checks naming the field, and a
planner without options reading no file."""

import builtins
import dataclasses as dc
import io
import pathlib
import re

import pytest
from pydrake.common.yaml import yaml_load_typed

import planning.planner_options as mut
from drake_sim.base.errors import ConfigError
from planning import ErrorCode, PlanningError, PlanningScene
from planning.motion_planner import MotionPlanner

REPO = pathlib.Path(__file__).resolve().parents[2]


def test_defaults_are_the_documented_values():
    """The values config/planner.yaml held before the dataclass defaults replaced it."""
    o = mut.MotionPlannerOptions()
    assert (o.timeout, o.seed) == (5.0, 0)
    assert o.rrt == mut.RrtConnectOptions(
        step=0.5,
        goal_bias=0.05,
        balance=True,
        dynamic_domain=4.0,
        dynamic_domain_min=1.0,
        batch=16,
        restart_interval=10.0,
    )
    assert o.shortcut == mut.ShortcutOptions(iterations=30, time_fraction=0.2)
    assert o.validation == mut.ValidationOptions(
        resolution=0.01,
        max_repairs=3,
        repair_timeout=0.5,
        repair_step=0.25,
        repair_resolution=0.03,
        swept=True,
    )
    assert o.pose == mut.PoseGoalOptions(ik_solutions=4)
    assert o.cartesian == mut.CartesianOptions(step=0.005, rotation_step=0.05, jump_threshold=0.2)
    assert o.timing == mut.TimingOptions(  # no limits: the robot's (the Panda's datasheet)
        max_velocity=[], max_acceleration=[], velocity_scaling=1.0, acceleration_scaling=1.0
    )
    assert o.kto == mut.KtoOptions(enabled=False)
    assert o.spheres == mut.SphereCheckOptions(
        enabled=True,
        slack=0.015,
        drake_fallback_after=1_000_000,
        search_resolution=0.1,
        anchor_radius=0.15,
        refine_slack=0.005,
    )
    o.check()


def test_sections_are_not_shared_between_instances():
    a, b = mut.MotionPlannerOptions(), mut.MotionPlannerOptions()
    a.timing.max_velocity.append(1.0)
    assert b.timing.max_velocity == [] and b.rrt is not a.rrt


def test_nested_yaml_loads_and_keeps_the_other_defaults(tmp_path):
    path = tmp_path / "planner.yaml"
    path.write_text(
        "timeout: 2.0\nseed: 7\nrrt: {step: 0.5, batch: 8}\ntiming: {velocity_scaling: 0.5}\n"
        "spheres:\n  enabled: false\n"
    )
    options = mut.load_planner_options(path)
    expected = mut.MotionPlannerOptions(
        timeout=2.0,
        seed=7,
        rrt=mut.RrtConnectOptions(step=0.5, batch=8),
        timing=mut.TimingOptions(velocity_scaling=0.5),
        spheres=mut.SphereCheckOptions(enabled=False),
    )
    assert options == expected
    assert mut.load_planner_options(str(path)) == expected  # a str filename too


def test_empty_yaml_gives_the_defaults():
    options = yaml_load_typed(schema=mut.MotionPlannerOptions, data="{}")
    assert options == mut.MotionPlannerOptions()


@pytest.mark.parametrize(
    "text, key",
    [
        ("rrt: {bogus: 1}\n", "bogus"),
        ("rrt_step: 1.0\n", "rrt_step"),  # the old flat names are unknown now
        ("sphere_checks: false\n", "sphere_checks"),
    ],
)
def test_unknown_keys_are_rejected(tmp_path, text, key):
    path = tmp_path / "planner.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=key):
        mut.load_planner_options(path)


def test_load_checks_the_ranges(tmp_path):
    path = tmp_path / "planner.yaml"
    path.write_text("validation: {resolution: 0.05}\n")
    with pytest.raises(ConfigError, match=r"planner.yaml: validation\.resolution must be"):
        mut.load_planner_options(path)


def test_load_needs_a_filename():
    with pytest.raises(TypeError):
        mut.load_planner_options()


BAD_VALUES = [
    ("rrt", "step", 0.0),
    ("rrt", "goal_bias", 1.5),
    ("rrt", "balance", 1),
    ("rrt", "dynamic_domain", -1.0),
    ("rrt", "dynamic_domain", float("nan")),
    ("rrt", "dynamic_domain", float("inf")),
    ("rrt", "dynamic_domain_min", 0.0),
    ("rrt", "dynamic_domain_min", float("inf")),
    ("rrt", "batch", 0),
    ("rrt", "restart_interval", -1.0),
    ("shortcut", "iterations", -1),
    ("shortcut", "time_fraction", 1.5),
    ("validation", "resolution", 0.05),
    ("validation", "resolution", 0.0),
    ("validation", "max_repairs", -1),
    ("validation", "repair_timeout", 0.0),
    ("validation", "repair_step", 0.0),
    ("validation", "repair_resolution", 0.0),
    ("validation", "repair_resolution", float("inf")),
    ("validation", "repair_resolution", float("nan")),
    ("validation", "swept", "yes"),
    ("pose", "ik_solutions", 0),
    ("cartesian", "step", 0.0),
    ("cartesian", "rotation_step", 0.0),
    ("cartesian", "jump_threshold", -0.1),
    ("timing", "max_velocity", [2.0] * 6 + [-1.0]),
    ("timing", "max_acceleration", [10.0] * 6 + [0.0]),
    ("timing", "velocity_scaling", 1.5),
    ("timing", "acceleration_scaling", 0.0),
    ("kto", "enabled", "yes"),
    ("spheres", "enabled", 1),
    ("spheres", "slack", 0.0),
    ("spheres", "drake_fallback_after", -1),
    ("spheres", "search_resolution", 0.0),
    ("spheres", "anchor_radius", -0.1),
    ("spheres", "anchor_radius", float("inf")),
    ("spheres", "refine_slack", -0.001),
    ("spheres", "refine_slack", 0.015),  # not tighter than the first cover
]


@pytest.mark.parametrize("section, field, value", BAD_VALUES)
def test_each_section_check_names_the_field(section, field, value):
    name = re.escape(f"{section}.{field}")
    bad = dc.replace(getattr(mut.MotionPlannerOptions(), section), **{field: value})
    with pytest.raises(ValueError, match=rf"^{name} must be"):
        bad.check()  # the section alone, named by its default prefix
    with pytest.raises(ValueError, match=rf"^{name} must be"):
        mut.MotionPlannerOptions(**{section: bad}).check()


BAD_TIMEOUTS = [0.0, -1.0, float("nan"), float("inf"), -float("inf"), True, "5"]


@pytest.mark.parametrize(
    "field, value",
    [*(("timeout", t) for t in BAD_TIMEOUTS), ("seed", -1), ("seed", 1.5)],
)
def test_top_level_check_names_the_field(field, value):
    with pytest.raises(ValueError, match=rf"^{field} must be"):
        mut.MotionPlannerOptions(**{field: value}).check()


def test_a_timeout_that_is_not_finite_seconds_is_refused_when_the_planner_is_made():
    """Before the planner compiles or searches anything (the check comes first)."""
    with pytest.raises(ValueError, match=r"^timeout must be a finite number of seconds > 0"):
        MotionPlanner(None, mut.MotionPlannerOptions(timeout=float("nan")))


@pytest.mark.parametrize("timeout", BAD_TIMEOUTS)
def test_request_timeout_refuses_what_is_not_finite_seconds(timeout):
    with pytest.raises(PlanningError) as info:
        mut.request_timeout(timeout, 5.0)
    assert info.value.code is ErrorCode.INVALID_MOTION_PLAN
    assert info.value.message == (
        f"invalid request: timeout must be a finite number of seconds > 0, got {timeout!r}"
    )


def test_request_timeout_takes_the_options_when_none():
    assert mut.request_timeout(None, 5.0) == 5.0
    assert mut.request_timeout(0.25, 5.0) == 0.25
    assert mut.request_timeout(2, 5.0) == 2.0 and isinstance(mut.request_timeout(2, 5.0), float)
    with pytest.raises(PlanningError, match=r"options\.timeout must be .*, got nan"):
        mut.request_timeout(None, float("nan"))  # options changed after the check


def test_replace_keeps_working_on_top_level_fields():
    options = dc.replace(mut.MotionPlannerOptions(), seed=3, timeout=1.0)
    assert (options.seed, options.timeout) == (3, 1.0)
    assert options.rrt == mut.RrtConnectOptions()
    options.check()


def test_planner_without_options_reads_no_file(monkeypatch):
    """The defaults are the dataclass's: no config/planner.yaml, no YAML read at all."""
    assert not (REPO / "config" / "planner.yaml").exists()
    scene = PlanningScene()
    opened = []

    def spy(real):
        def open_and_record(file, *args, **kwargs):
            opened.append(str(file))
            return real(file, *args, **kwargs)

        return open_and_record

    def no_yaml(*args, **kwargs):
        raise AssertionError("MotionPlanner read a YAML file")

    monkeypatch.setattr(builtins, "open", spy(builtins.open))
    monkeypatch.setattr(io, "open", spy(io.open))
    monkeypatch.setattr(pathlib.Path, "open", spy(pathlib.Path.open))
    monkeypatch.setattr(mut, "load_typed", no_yaml)
    planner = MotionPlanner(scene)
    robot = scene.model.robot  # the timing limits the planner fills in are the robot's
    expected = mut.MotionPlannerOptions()
    expected.timing = expected.timing.with_robot_limits(robot)
    assert planner.options == expected
    assert not [f for f in opened if f.endswith((".yaml", ".yml"))]
