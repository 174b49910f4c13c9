"""Two checkouts of this project side by side on the MotionBenchMaker problems, interleaved.

    python benchmarks/planner_ab.py OLD_CHECKOUT NEW_CHECKOUT [--limit 1000] [--families F ...]
        [--timeout 5] [--set section.field=value ...] [--dataset PATH]

Each checkout runs in a worker process of its own (its own ``planning`` package and numba cache:
compile each once first, e.g. with ``python -m planning.benchmark --limit 1`` in it). The driver
hands every problem to one worker, then to the other, alternating which goes first, and only
one of them works at a time: both see the same machine, whatever its speed is doing, and the
other core stays idle. Each worker times ``MotionPlanner.plan_path`` as ``python -m
planning.benchmark`` does (scene loaded and ``prepare``d untimed). ``--set`` changes an option
of NEW's planner (``shortcut.iterations=40``), to compare options on one checkout. Both sides
plan the same problem files: the driver finds them once, as ``python -m planning.benchmark`` does
(``--dataset``, else ``$DRAKE_SIM_MBM``, the cache, or a download with pip into the cache; see
``planning.io.mbm.find_problems``), and hands the folder to both workers.

Prints both sides' median, p95 and mean (ms), their median path lengths, the median over the
problems of NEW's time over OLD's, the ratio of the total times, the share of problems with the
same path length, and the per-problem median ratio per family. Exit code 2, with one line on
stderr, on bad arguments, a worker that fails, or a problem one side solves and the other not.

Why interleaved: two ``planning.benchmark`` runs at once, one per core of this project's 2-core
VM, disagreed with themselves by up to 10 % per family and 8 % overall (the same pair of commits
gave 0.90x as two steps and 1.03x at once), while the same checkout against itself here gives a
per-problem median ratio of 0.999 (families within 1 %).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from drake_sim.base import cli
from drake_sim.base.errors import ConfigError

READY = "ready"


# -------------------------------------------------------------------------- worker ----
def worker(checkout: Path, timeout: float, settings: list[str], folder: Path) -> None:
    """Reads problem indices on stdin and answers each with a JSON line: [index, time (s) or
    None when the problem is invalid, path length (rad) or None when it failed, family]. Each
    problem, of the MBM problems folder ``folder``, is ``planning.benchmark.run_problem``'s,
    timed as that benchmark times it."""
    sys.path.insert(0, str(checkout))
    import planning
    from drake_sim.tools.plan_benchmark import run_problem
    from planning.io import mbm
    from planning.motion_planner import MotionPlanner, MotionPlannerOptions

    if not Path(planning.__file__).resolve().is_relative_to(checkout.resolve()):
        raise SystemExit(f"planning came from {planning.__file__}, not from {checkout}")
    try:
        options = with_settings(MotionPlannerOptions(), settings)
    except ValueError as e:
        print(json.dumps(["error", str(e)]), flush=True)
        return
    scene = planning.PlanningScene()
    planner = MotionPlanner(scene, options)
    problems = list(mbm.iter_problems(folder, None, 100_000))
    print(json.dumps([READY, [[p.family, p.number] for p in problems]]), flush=True)
    for line in sys.stdin:
        problem = problems[int(line)]
        row = run_problem(scene, planner, problem, timeout)
        elapsed = row["time_s"] if row["valid"] else None
        print(json.dumps([int(line), elapsed, row["path_length"], problem.family]), flush=True)


def with_settings(options, settings: list[str]):
    """``options`` (``MotionPlannerOptions``) with each "section.field=value" of ``settings``
    set, the value converted to the field's type ("true"/"false" for a bool), then checked.

    Raises:
        ValueError: naming the setting, for an unknown name or a value that does not convert
            or that the options reject.
    """
    import dataclasses as dc

    for setting in settings:
        try:
            name, value = setting.split("=", 1)
            section, field = name.split(".")
            part = getattr(options, section)
            kind = type(getattr(part, field))
            if kind is bool:  # bool("false") is True
                if value.lower() not in ("true", "false"):
                    raise ValueError(f"expected true or false, got {value!r}")
                value = value.lower() == "true"
            options = dc.replace(options, **{section: dc.replace(part, **{field: kind(value)})})
            options.check()  # out-of-range values name their field
        except (AttributeError, TypeError, ValueError) as e:
            raise ValueError(f"--set {setting}: {e}") from e
    return options


# -------------------------------------------------------------------------- driver ----
class _Side:
    """A worker process for one checkout."""

    def __init__(self, checkout: Path, timeout: float, settings: list[str], folder: Path):
        command = [sys.executable, __file__, "--worker", str(checkout), "--timeout", str(timeout)]
        command += ["--dataset", str(folder)]
        command += [f"--set={s}" for s in settings]
        self.process = subprocess.Popen(
            command,
            cwd=checkout,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
            env=dict(os.environ, PYTHONPATH=str(checkout)),
        )
        tag, self.problems = self._read()
        if tag != READY:
            raise RuntimeError(f"{checkout}: {self.problems}")

    def _read(self):
        line = self.process.stdout.readline()
        if not line:
            raise RuntimeError("a worker stopped (run it alone to see why)")
        return json.loads(line)

    def run(self, index: int):
        self.process.stdin.write(f"{index}\n")
        self.process.stdin.flush()
        return self._read()

    def close(self) -> None:
        self.process.stdin.close()
        self.process.wait()


def schedule(indices: list[int]) -> list[tuple[int, bool]]:
    """(problem, OLD first?) in turn: OLD goes first on every other problem."""
    return [(index, k % 2 == 0) for k, index in enumerate(indices)]


def summarize(rows: list[tuple[str, float, float, float | None, float | None]]) -> str:
    """The report of rows (family, OLD s, NEW s, OLD length, NEW length) of valid problems."""
    family = np.array([r[0] for r in rows])
    old = np.array([r[1] for r in rows]) * 1e3
    new = np.array([r[2] for r in rows]) * 1e3
    lengths = np.array([[np.nan if x is None else x for x in r[3:]] for r in rows], dtype=float)
    ratio = new / old
    same = np.isclose(lengths[:, 0], lengths[:, 1], equal_nan=True)
    lines = [
        f"{len(rows)} problems, ms: OLD median {np.median(old):.3f} p95 "
        f"{np.percentile(old, 95):.2f} mean {old.mean():.3f} | NEW median {np.median(new):.3f} "
        f"p95 {np.percentile(new, 95):.2f} mean {new.mean():.3f}",
        f"median path length: OLD {np.nanmedian(lengths[:, 0]):.3f} rad, "
        f"NEW {np.nanmedian(lengths[:, 1]):.3f} rad; the same length on {same.mean():.0%}",
        f"NEW / OLD: per-problem median {np.median(ratio):.3f}, total {new.sum() / old.sum():.3f}",
    ]
    for name in sorted(set(family)):
        m = family == name
        lines.append(
            f"  {name:24s} OLD {np.median(old[m]):6.2f}  NEW {np.median(new[m]):6.2f}  "
            f"ratio {np.median(ratio[m]):.3f}"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    """Runs the comparison; bad input is one stderr line and exit code 2 (``cli.run``)."""
    return cli.run(_main, argv)


def _main(argv) -> int:
    parser = cli.ArgumentParser(prog="benchmarks/planner_ab.py", description=__doc__.split("\n")[0])
    parser.add_argument("old", type=Path, nargs="?", help="the checkout to compare against")
    parser.add_argument("new", type=Path, nargs="?", help="the checkout to measure")
    parser.add_argument("--limit", type=int, default=1000, help="problems per family")
    parser.add_argument("--families", nargs="+", help="only these families")
    parser.add_argument("--timeout", type=float, default=5.0, help="s per request")
    parser.add_argument("--set", action="append", default=[], help="NEW's option: a.b=value")
    parser.add_argument(
        "--dataset",
        type=cli.input_path("dataset"),
        metavar="PATH",
        help="MBM problems folder or problems.tar.bz2 (default: as planning.benchmark finds it)",
    )
    parser.add_argument("--worker", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker is not None:
        worker(args.worker, args.timeout, args.set, args.dataset)
        return 0
    if args.old is None or args.new is None:
        parser.error("give two checkouts, OLD and NEW")
    # The workers (and their own planners' builds) use the compiled planner from the first
    # problem, waiting for it on a fresh install.
    os.environ["DRAKE_SIM_KERNELS"] = "wait"
    for checkout in (args.old, args.new):
        if not (checkout / "planning" / "__init__.py").is_file():
            parser.error(f"{checkout} is not a checkout of this project (no planning/)")
    for setting in args.set:
        if "=" not in setting or setting.split("=")[0].count(".") != 1:
            parser.error(f"--set {setting}: expected section.field=value")
    from planning.io import mbm  # here, not above: a worker imports its own checkout's

    folder = mbm.find_problems(args.dataset).resolve()  # MbmDataError: one line, exit code 2
    try:
        print(compare(args, folder))
    except RuntimeError as e:  # a worker failed, or one side alone failed a problem
        raise ConfigError(str(e)) from e
    return 0


def compare(args, folder: Path) -> str:
    """Runs both sides on the chosen problems of the MBM problems folder ``folder``; returns
    ``summarize``'s report. Raises RuntimeError when a worker fails, or when one side fails a
    problem the other solves."""
    old = _Side(args.old, args.timeout, [], folder)
    new = _Side(args.new, args.timeout, args.set, folder)
    seen: dict[str, int] = {}
    indices = []
    for k, (family, _) in enumerate(old.problems):
        if (args.families is None or family in args.families) and seen.get(family, 0) < args.limit:
            seen[family] = seen.get(family, 0) + 1
            indices.append(k)
    rows, failed = [], []
    for index, old_first in schedule(indices):
        first, second = (old, new) if old_first else (new, old)
        a, b = first.run(index), second.run(index)
        r_old, r_new = (a, b) if old_first else (b, a)
        if r_old[1] is None:
            continue  # start or goal invalid under the model
        if (r_old[2] is None) != (r_new[2] is None):
            failed.append(f"{r_old[3]} {old.problems[index][1]}")
        rows.append((r_old[3], r_old[1], r_new[1], r_old[2], r_new[2]))
    old.close()
    new.close()
    if not rows:
        raise RuntimeError("no valid problem was chosen")
    report = summarize(rows)
    if failed:
        raise RuntimeError(f"{report}\none side only failed: {', '.join(failed)}")
    return report


if __name__ == "__main__":
    sys.exit(main())
