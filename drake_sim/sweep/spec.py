"""A sweep file, parsed and checked, and the deterministic list of rollouts it stands for.

Everything here is plain data (dicts, numbers, strings) so that a rollout can cross a process
or machine boundary unchanged; nothing Drake is built here. The rollout list depends only on
the file and its ``seed``: the same file gives the same rollouts, seeds and random draws on any
backend and with any number of workers.
"""

import dataclasses as dc
import itertools
import math
import re
from pathlib import Path

import numpy as np

from drake_sim.base.config import parse_key_path, parse_yaml, read_text
from drake_sim.base.errors import ConfigError
from drake_sim.sweep.table import FIRST_COLUMNS, LAST_COLUMNS

TOP_KEYS = (
    "name",
    "runner",
    "scenario",
    "options",
    "seed",
    "samples",
    "repeats",
    "parameters",
    "metrics",
    "success",
)
DISTRIBUTIONS = ("grid", "uniform", "normal", "choice", "random")
# Kinds enumerated like a grid: ``random: N`` is the numbers 0 to N - 1 of values the runner
# generates (``scene: {random: 200}``: pick-and-place scenes 0 to 199).
ENUMERATED = ("grid", "random")
_COMPARISON = re.compile(r"^\s*([A-Za-z_]\w*)\s*(>=|<=|==|!=|>|<)\s*(\S.*?)\s*$")
_SEED_BITS = 31  # Per-rollout seeds fit a signed 32-bit int (Drake's RandomGenerator takes them).


@dc.dataclass(frozen=True)
class Parameter:
    """One varied value: its dotted path in the runner's scenario and how it is varied."""

    path: str  # A --set key: "flip.drive_speed", "robot.body.mass", "scene.object.position[1]".
    kind: str  # One of DISTRIBUTIONS.
    values: tuple  # grid/choice: the values; uniform: (low, high); normal: (mean, sigma).


@dc.dataclass(frozen=True)
class Condition:
    """A success test on one report key: ``key op value`` (``op`` None: the key is truthy)."""

    key: str
    op: str | None = None
    value: object = None

    def holds(self, metrics: dict) -> bool:
        actual = metrics.get(self.key)
        if self.op is None:
            return bool(actual)
        if actual is None:
            return False
        ops = {
            ">=": lambda a, b: a >= b,
            "<=": lambda a, b: a <= b,
            ">": lambda a, b: a > b,
            "<": lambda a, b: a < b,
            "==": lambda a, b: a == b,
            "!=": lambda a, b: a != b,
        }
        try:
            return bool(ops[self.op](actual, self.value))
        except TypeError:
            return False


@dc.dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep file (see the package docstring for its keys)."""

    name: str
    runner: str
    scenario: str | None  # Absolute path, or None for the runner's default.
    options: dict
    seed: int
    samples: int
    repeats: int
    parameters: tuple[Parameter, ...]
    metrics: tuple[str, ...]
    success: tuple[Condition, ...]
    source: str  # The sweep file, for messages.

    @property
    def grid(self) -> tuple[Parameter, ...]:
        return tuple(p for p in self.parameters if p.kind in ENUMERATED)

    @property
    def random(self) -> tuple[Parameter, ...]:
        return tuple(p for p in self.parameters if p.kind not in ENUMERATED)

    @property
    def size(self) -> int:
        """How many rollouts the sweep has."""
        return math.prod(len(p.values) for p in self.grid) * self.samples * self.repeats


@dc.dataclass(frozen=True)
class Rollout:
    """One run of the sweep: everything a worker needs to build and run it, as plain data."""

    index: int
    seed: int
    overrides: dict  # path -> value, in the sweep file's parameter order.


def load_sweep(filename: Path | str) -> SweepSpec:
    """Reads and checks a sweep file (structure and values; the runner checks the paths).

    Raises:
        ConfigError: naming the file and the key at fault.
    """
    path = Path(filename)
    where = str(path)
    tree = parse_yaml(read_text(path, "sweep file"), where)
    if not isinstance(tree, dict):
        raise ConfigError(f"{where}: expected a mapping with keys {', '.join(TOP_KEYS)}")
    for key in tree:
        if key not in TOP_KEYS:
            raise ConfigError(f"{where}: unknown key '{key}' (known: {', '.join(TOP_KEYS)})")
    runner = tree.get("runner")
    if not isinstance(runner, str) or not runner:
        raise ConfigError(f"{where}: 'runner' must name a runner (e.g. flip, pickplace)")
    scenario = tree.get("scenario")
    if scenario is not None:
        if not isinstance(scenario, str) or not scenario:
            raise ConfigError(f"{where}: 'scenario' must be a file path")
        scenario = str(_resolve(scenario, path))
    options = tree.get("options") or {}
    if not isinstance(options, dict):
        raise ConfigError(f"{where}: 'options' must be a mapping")
    options = {k: _finite(v, where, f"options.{k}") for k, v in options.items()}
    parameters = tree.get("parameters") or {}
    if not isinstance(parameters, dict):
        raise ConfigError(f"{where}: 'parameters' must be a mapping of path: distribution")
    metrics = tree.get("metrics") or []
    if not isinstance(metrics, list) or not all(isinstance(m, str) and m for m in metrics):
        raise ConfigError(f"{where}: 'metrics' must be a list of report keys")
    if len(set(metrics)) != len(metrics):
        raise ConfigError(f"{where}: 'metrics' lists a key twice")
    for key in metrics:
        if key in (*FIRST_COLUMNS, *LAST_COLUMNS) or key in parameters:
            raise ConfigError(
                f"{where}: metric '{key}' is already a column of the table (its own "
                "status, success, wall time and reason): drop it from 'metrics' (a boolean "
                f"report key can be the test: success: {key})"
            )
    return SweepSpec(
        name=_name(tree.get("name", path.stem), where),
        runner=runner,
        scenario=scenario,
        options=options,
        seed=_count(tree.get("seed", 0), where, "seed", minimum=0),
        samples=_count(tree.get("samples", 1), where, "samples"),
        repeats=_count(tree.get("repeats", 1), where, "repeats"),
        parameters=tuple(_parameter(k, v, where) for k, v in parameters.items()),
        metrics=tuple(metrics),
        success=_success(tree.get("success"), where),
        source=where,
    )


def rollouts(spec: SweepSpec) -> list[Rollout]:
    """The sweep's rollouts, in order: grid points (the first parameter varies slowest), then
    ``samples`` random draws at each, then ``repeats`` seeds of each draw.

    Draw ``d`` (0 to ``samples - 1``) comes from ``default_rng([seed, 1, d])`` and repeat ``r``
    of it gets the seed ``SeedSequence([seed, 2, d, r])``: nothing depends on how or where
    rollouts run. Every grid point sees the same draws and seeds (common random numbers), so
    grid points are compared on the same random scenes and noise, not on luck.
    """
    grid = spec.grid
    draws = []
    for d in range(spec.samples):
        rng = np.random.default_rng([spec.seed, 1, d])
        values = {p.path: _draw(p, rng) for p in spec.random}
        seeds = [
            int(np.random.SeedSequence([spec.seed, 2, d, r]).generate_state(1)[0])
            & ((1 << _SEED_BITS) - 1)
            for r in range(spec.repeats)
        ]
        draws.append((values, seeds))
    out = []
    for point in itertools.product(*(p.values for p in grid)):
        fixed = dict(zip((p.path for p in grid), point, strict=True))
        for values, seeds in draws:
            ordered = {p.path: {**fixed, **values}[p.path] for p in spec.parameters}
            for seed in seeds:
                out.append(Rollout(index=len(out), seed=seed, overrides=ordered))
    return out


def _draw(p: Parameter, rng: np.random.Generator):
    if p.kind == "uniform":
        return float(rng.uniform(*p.values))
    if p.kind == "normal":
        return float(rng.normal(*p.values))
    return p.values[int(rng.integers(len(p.values)))]  # choice


def _parameter(path, spec, where: str) -> Parameter:
    if not isinstance(path, str):
        raise ConfigError(
            f"{where}: parameter {path!r} is not a dotted path (e.g. flip.drive_speed, "
            "scene.object.position[0])"
        )
    parse_key_path(path, f"{where}: parameter {path!r} is not a dotted path")
    at = f"{where}: parameter '{path}'"
    if not isinstance(spec, dict) or len(spec) != 1:
        raise ConfigError(f"{at} must be one of {{{': ..., '.join(DISTRIBUTIONS)}: ...}}")
    ((kind, values),) = spec.items()
    if kind not in DISTRIBUTIONS:
        raise ConfigError(
            f"{at}: unknown distribution {kind!r} (known: {', '.join(DISTRIBUTIONS)})"
        )
    if kind == "random":
        if isinstance(values, bool) or not isinstance(values, int) or values < 1:
            raise ConfigError(f"{at}: random needs a count >= 1 (random: 200), got {values!r}")
        return Parameter(path=path, kind=kind, values=tuple(range(values)))
    if not isinstance(values, list) or not values:
        raise ConfigError(f"{at}: {kind} needs a non-empty list")
    values = [_finite(v, where, f"{path}.{kind}") for v in values]
    if kind in ("uniform", "normal"):
        if len(values) != 2 or not all(_is_number(v) for v in values):
            what = "[low, high]" if kind == "uniform" else "[mean, sigma]"
            raise ConfigError(f"{at}: {kind} needs two numbers {what}, got {values}")
        if kind == "uniform" and not values[0] < values[1]:
            raise ConfigError(f"{at}: uniform [low, high] needs low < high, got {values}")
        if kind == "normal" and not values[1] >= 0:
            raise ConfigError(f"{at}: normal [mean, sigma] needs sigma >= 0, got {values}")
        values = [float(v) for v in values]
    return Parameter(path=path, kind=kind, values=tuple(values))


def _success(spec, where: str) -> tuple[Condition, ...]:
    if spec is None:
        return ()
    items = spec if isinstance(spec, list) else [spec]
    out = []
    for item in items:
        if not isinstance(item, str) or not item.strip():
            raise ConfigError(f"{where}: 'success' must be a report key or 'KEY OP VALUE'")
        match = _COMPARISON.match(item)
        if match is None:
            if not re.match(r"^[A-Za-z_]\w*$", item.strip()):
                raise ConfigError(
                    f"{where}: 'success' entry {item!r} is not KEY or KEY OP VALUE "
                    "(OP one of >= <= > < == !=)"
                )
            out.append(Condition(key=item.strip()))
            continue
        key, op, text = match.groups()
        try:
            value = parse_yaml(text, where)
        except ConfigError:
            value = None
        if value is None or isinstance(value, dict | list):
            raise ConfigError(
                f"{where}: 'success' entry {item!r} is not KEY or KEY OP VALUE "
                "(VALUE a number, true, false or a word)"
            )
        out.append(Condition(key=key, op=op, value=_finite(value, where, "success")))
    return tuple(out)


def _resolve(text: str, sweep_file: Path) -> Path:
    """A path in a sweep file is relative to the file's folder."""
    path = Path(text)
    return path if path.is_absolute() else (sweep_file.parent / path).resolve()


def _name(value, where: str) -> str:
    if not isinstance(value, str) or not re.match(r"^[\w.-]+$", value):
        raise ConfigError(f"{where}: 'name' must be letters, digits, '_', '-' or '.'")
    return value


def _count(value, where: str, key: str, *, minimum: int = 1) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise ConfigError(f"{where}: '{key}' must be an integer >= {minimum}, got {value!r}")
    return value


def _is_number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _finite(value, where: str, key: str):
    """``value`` unchanged, unless it is (or holds) a NaN or infinite number."""
    if isinstance(value, list):
        return [_finite(v, where, key) for v in value]
    if isinstance(value, dict):
        return {k: _finite(v, where, f"{key}.{k}") for k, v in value.items()}
    if isinstance(value, float) and not math.isfinite(value):
        raise ConfigError(f"{where}: '{key}' must be finite, got {value!r}")
    if isinstance(value, str) and value.strip().lower().lstrip("+-") in (
        ".nan",
        "nan",
        ".inf",
        "inf",
    ):
        raise ConfigError(f"{where}: '{key}' must be a finite number, got {value!r}")
    return value
