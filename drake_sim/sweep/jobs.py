"""A sweep's plain-data job, checked before anything runs (``make_job``): the runner, its
options, and each parameter path naming a value of its scenario (``resolve``)."""

import dataclasses as dc
from pathlib import Path

from drake_sim.base import config
from drake_sim.base.errors import ConfigError
from drake_sim.sweep.runners import get_runner


def resolve(value, path: str, where: str):
    """The value at ``path`` (a ``--set`` key: ``a.b[2]``, ``m[1][0]``) inside dataclass
    ``value``.

    Raises:
        ConfigError: naming the first part of the path that does not exist.
    """
    steps = config.parse_key_path(path, f"{where}: parameter path")
    walked = []
    for step in steps:
        if isinstance(step, int):
            here = config.format_key_path(walked)
            if not isinstance(value, list | tuple) or step >= len(value):
                raise ConfigError(f"{where}: parameter path '{path}': {here} has no item {step}")
            value = value[step]
        elif not dc.is_dataclass(value) or step not in {f.name for f in dc.fields(value)}:
            known = ", ".join(f.name for f in dc.fields(value)) if dc.is_dataclass(value) else ""
            here = config.format_key_path(walked) or "the scenario"
            hint = f" (known in {here}: {known})" if known else ""
            raise ConfigError(f"{where}: unknown parameter path '{path}'{hint}")
        else:
            value = getattr(value, step)
        walked.append(step)
    if dc.is_dataclass(value):
        raise ConfigError(f"{where}: parameter path '{path}' is a section, not a value")
    return value


def make_job(spec) -> dict:
    """The plain-data job of a ``SweepSpec``, checked before anything runs: the runner exists,
    its options are known, each parameter path names a value of its scenario, and each metric
    and success key is one of its report's.

    Raises:
        ConfigError: naming the sweep file and what is wrong.
    """
    where = spec.source
    runner = get_runner(spec.runner, where)
    options = dict(runner.options)
    for key, value in spec.options.items():
        if key not in runner.options:
            known = ", ".join(runner.options) or "none"
            raise ConfigError(f"{where}: unknown option '{key}' for {runner.name} (known: {known})")
        if key in runner.file_options and value is not None:
            path = Path(str(value))
            value = str(path if path.is_absolute() else (Path(where).parent / path).resolve())
        options[key] = value
    scenario = spec.scenario or str(runner.app().RECIPE.scenario.default_file())
    generated = getattr(runner, "generated", ())
    for p in spec.parameters:
        if p.kind == "random" and p.path not in generated:
            names = ", ".join(generated) or "nothing"
            raise ConfigError(
                f"{where}: parameter '{p.path}': random draws values the runner generates, "
                f"and {runner.name} generates {names}"
            )
    if any(p.kind == "random" for p in spec.parameters):
        clash = [
            p.path
            for p in spec.parameters
            if p.kind != "random"
            and p.path.split(".")[0] in {q.path for q in spec.parameters if q.kind == "random"}
        ]
        if clash:
            raise ConfigError(
                f"{where}: parameter '{clash[0]}' is inside a generated value (random)"
            )
    plain = [p.path for p in spec.parameters if p.kind != "random"]
    inputs = runner.load(scenario, options, {})
    for path in plain:
        if path.startswith("robot.") and inputs.robot is not None:
            resolve(inputs.robot, path[len("robot.") :], where)
        else:
            resolve(inputs.scenario, path, where)
    known = runner.metric_keys()
    for key in (*spec.metrics, *(c.key for c in spec.success)):
        if key not in known:
            raise ConfigError(
                f"{where}: '{key}' is not a {runner.name} report key (known: {', '.join(known)})"
            )
    return {"runner": runner.name, "scenario": scenario, "options": options}
