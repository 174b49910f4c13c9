"""``python -m planning.benchmark``: MotionPlanner on MotionBenchMaker problems (the Panda's, or
another robot's with ``--robot``).

Usage::

    python -m planning.benchmark [--dataset PATH] --limit 5 --timeout 5 --report report.json \\
        [--families box_panda cage_panda] [--compare-ompl] [--plot times.png]
    python -m planning.benchmark --random 20 --seed 1 [--save-problems DIR] ...

The MotionBenchMaker problems are third-party data, not part of the repository:
``planning.io.mbm.find_problems`` takes them from ``--dataset`` (a ``problems`` folder, a folder
holding ``problems.tar.bz2``, or the archive itself, unpacked once into the cache), else from
``$DRAKE_SIM_MBM`` (the same forms), else from the cache (``<cache>/mbm/panda``), else it
downloads them once from the package index with pip (the ``vamp-planner`` source distribution,
about 65 MB) into the cache. For each problem the scene is loaded, the joints outside the
planning group are set to the request's start state, a start within ``START_BOUNDS_ERROR``
outside the limits is moved onto them (MoveIt's FixStartStateBounds), as is a goal within
``GOAL_ROUNDING`` (the limits' rounding), and the start and goal
are checked (``valid``: in limits and collision-free under our model); valid problems are
planned with ``MotionPlanner.plan_path`` (the checks and the
search of ``plan_to_joints``, without the time parametrisation) and timed from request to
validated path. Each report row has ``family``, ``problem``, ``valid``, ``success``,
``time_s``, ``path_length`` (joint-space L2, rad), ``path_valid_fine`` (re-checked here at
0.01 rad), ``path`` (7-joint waypoints, straight-line interpolation), and ``planner``/``error``;
with ``--compare-ompl`` also ``ompl_success``, ``ompl_time_s``, ``ompl_path_length``,
``ompl_path_valid_fine`` (OMPL RRTConnect plus simplification on the same checker).
``--plot FILE`` writes a PNG with histograms of the times per problem (log scale), ours and
OMPL's. ``--profile`` prints where the time of each request goes (phases with exclusive
times, checks per request; ``drake_sim.tools.plan_benchmark_profile``) and times
``plan_to_joints``' time parametrisation apart, after the timed interval. A progress bar
(tqdm, when installed) runs on stderr. Paths are re-checked with Drake's checker alone
(``planning.collision.checker.CheckerAdapter``), whatever collision model the planner used.
``--random N --seed S`` plans N random problems instead
(``planning.task.random_problems``: 3 to 8 boxes and cylinders within the arm's reach and clear
of its base, a collision-free start and goal at least 1 rad apart with the straight line between
them blocked; deterministic for a seed, problem k the same whatever N); a problem that cannot be
made is a row with ``valid`` false and its ``error``. ``--save-problems DIR`` writes them as
``DIR/random/sceneNNNN.yaml`` (moveit_msgs/PlanningScene) and ``requestNNNN.yaml``
(MotionPlanRequest: the start's joints by name, one goal of joint constraints;
``planning.io.problem_files``), the layout of an MBM set: ``--dataset DIR`` runs them again.
Every row also has ``joint_names``, the planning group's joints in the order of ``path``.
Exit code 0 when the run completed, 2 on bad input or when the problems cannot be had (one line
on stderr: a path that is no set, a corrupt archive, a download that failed, ``--random``
with ``--dataset``, a folder that cannot be written).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from drake_sim.base import cli
from drake_sim.base.errors import ConfigError
from drake_sim.tools.ompl_baseline import ompl_available, ompl_plan
from drake_sim.tools.plan_benchmark_profile import PhaseProfiler, breakdown
from planning import planner_kernels
from planning.collision.checker import CheckerAdapter, first_invalid_segment
from planning.config import PlanningConfig, check_planning_config
from planning.errors import PlanningError
from planning.io import mbm, problem_files
from planning.motion_planner import MotionPlanner, MotionPlannerOptions, load_planner_options
from planning.paths import path_length
from planning.planning_scene import PlanningScene
from planning.task.random_problems import group_joint_names, random_problems, workspace_of

_FINE = 0.01  # rad
RANDOM_FAMILY = "random"
"""The family folder of random problems (``--random``, ``--save-problems``)."""


def robot_config(robot: str) -> PlanningConfig:
    """The planning configuration of ``--robot``: the Panda with its table (the MBM scenes
    replace it), any other robot without one."""
    config = PlanningConfig()
    if robot != "panda":
        config.model.description = robot
        config.table = None
    check_planning_config(config, f"--robot {robot}")
    return config


START_BOUNDS_ERROR = 0.05
"""rad (or m): a start this close outside the joint limits is moved onto them, as MoveIt's
default planning pipeline does (its FixStartStateBounds adapter, start_state_max_bounds_error);
MBM's Fetch starts lie up to 3e-6 rad beyond VAMP's limits of +-3.14159."""
GOAL_ROUNDING = 1e-5
"""rad (or m): a goal this close outside a limit is on it: the URDF's limits are rounded (VAMP's
Fetch gives pi as 3.14159, its goals reach 3.1415925); MoveIt would refuse any goal beyond."""


def _load(scene, problem):
    scene.load_moveit(problem.scene_file)
    q_start, q_goal, others = mbm.read_request(problem.request_file, scene.model.joint_names)
    scene.set_positions(others)
    lower, upper = scene.lower, scene.upper
    if np.all((q_start >= lower - START_BOUNDS_ERROR) & (q_start <= upper + START_BOUNDS_ERROR)):
        q_start = np.clip(q_start, lower, upper)
    if np.all((q_goal >= lower - GOAL_ROUNDING) & (q_goal <= upper + GOAL_ROUNDING)):
        q_goal = np.clip(q_goal, lower, upper)
    return q_start, q_goal


def run_problem(scene, planner, problem, timeout: float, profiler=None) -> dict:
    """Plans one problem and returns its report row; with a ``PhaseProfiler`` active, also
    records the request's phases (and times the path's time parametrisation apart)."""
    q_start, q_goal = _load(scene, problem)
    valid = all(
        scene.in_joint_limits(q, 1e-6) and scene.is_collision_free(q) for q in (q_start, q_goal)
    )
    row = {"family": problem.family, "problem": problem.number, "valid": bool(valid)}
    row.update(success=False, time_s=None, path_length=None, path_valid_fine=None, path=None)
    if not valid:
        row["error"] = "start or goal invalid under our model"
        return row
    planner.prepare()  # the scene's set-up, untimed (as VAMP's environment is in its benchmark)
    start = time.perf_counter()
    try:
        # The validated joint path, as OMPL's below (no time parametrisation).
        path, how = planner.plan_path(q_start, q_goal, timeout=timeout)
        row.update(success=True, planner=how)
    except PlanningError as e:
        path = None
        row["error"] = f"{e.code.name}: {e.message}"
    row["time_s"] = time.perf_counter() - start
    if profiler is not None:
        if path is not None:  # plan_to_joints' last step, outside the timed interval
            planner._make_plan(path, row["planner"], time.perf_counter())
        profiler.take(row["time_s"], f"{problem.family} {problem.number}")
    if path is not None:
        row.update(_path_fields(scene, path))
    return row


def run_ompl(scene, problem, row: dict, timeout: float) -> None:
    """Adds OMPL's fields to a valid problem's row."""
    q_start, q_goal = _load(scene, problem)
    start = time.perf_counter()
    ompl_path = ompl_plan(scene, q_start, q_goal, timeout)
    row["ompl_time_s"] = time.perf_counter() - start
    row["ompl_success"] = ompl_path is not None
    if ompl_path is not None:
        fields = _path_fields(scene, ompl_path)
        row["ompl_path_length"] = fields["path_length"]
        row["ompl_path_valid_fine"] = fields["path_valid_fine"]


def _path_fields(scene, path: np.ndarray) -> dict:
    bad = first_invalid_segment(CheckerAdapter(scene), path, _FINE)
    return {
        "path_length": path_length(path),
        "path_valid_fine": bad is None,
        "path": path.tolist(),
    }


def summarize(rows: list[dict]) -> str:
    """Returns the per-family table (valid, solved, median and p95 time, median length)."""
    compare = any("ompl_success" in r for r in rows)
    families = list(dict.fromkeys(r["family"] for r in rows))
    width = max([24, *map(len, families)])
    head = f"{'family':{width}s} {'valid':>5s} {'solved':>6s} {'med ms':>8s} {'p95 ms':>8s}"
    head += f" {'len':>6s} {'fine ok':>7s}"
    if compare:
        head += f" | {'ompl ok':>7s} {'med ms':>8s} {'p95 ms':>8s} {'len':>6s} {'fine ok':>7s}"
    lines = [head, "-" * len(head)]
    for family in [*families, "all"]:
        group = [r for r in rows if family in ("all", r["family"]) and r["valid"]]
        lines.append(f"{family:{width}s} {len(group):5d} " + _stats(group, compare))
    if compare:
        lines.append(speedup(rows))
    return "\n".join(lines)


def speedup(rows: list[dict]) -> str:
    """One line comparing times on the valid problems: OMPL's median over ours (each side's
    failures counted at the time they took, the timeout), the same over the problems both
    solved, and the median of the per-problem ratios."""
    valid = [r for r in rows if r["valid"] and r.get("ompl_time_s") and r["time_s"]]
    both = [r for r in valid if r["success"] and r.get("ompl_success")]
    if not valid:
        return "speed-up: no valid problem timed by both"

    def ratio(group):
        ours = np.median([r["time_s"] for r in group])
        return np.median([r["ompl_time_s"] for r in group]) / ours, ours

    all_ratio, _ = ratio(valid)
    text = f"speed-up (OMPL median / ours): {all_ratio:.1f}x over {len(valid)} valid problems"
    if both:
        both_ratio, ours = ratio(both)
        per = np.median([r["ompl_time_s"] / r["time_s"] for r in both])
        text += (
            f"; {both_ratio:.1f}x over the {len(both)} both solved (ours {ours * 1e3:.1f} ms), "
            f"per-problem median ratio {per:.1f}x"
        )
    return text


def _stats(group: list[dict], compare: bool) -> str:
    def block(prefix: str) -> str:
        solved = [r for r in group if r.get(f"{prefix}success")]
        times = [r[f"{prefix}time_s"] * 1e3 for r in group if r.get(f"{prefix}time_s") is not None]
        lengths = [r[f"{prefix}path_length"] for r in solved]
        fine = sum(bool(r.get(f"{prefix}path_valid_fine")) for r in solved)
        if not times:
            return f"{len(solved):6d} {'-':>8s} {'-':>8s} {'-':>6s} {fine:7d}"
        return (
            f"{len(solved):6d} {np.median(times):8.1f} {np.percentile(times, 95):8.1f} "
            f"{(np.median(lengths) if lengths else float('nan')):6.2f} {fine:7d}"
        )

    text = block("")
    if compare:
        text += " | " + block("ompl_").lstrip()
    return text


def _parse_args(argv):
    parser = cli.ArgumentParser(
        prog="python -m planning.benchmark",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--dataset",
        type=cli.input_path("dataset"),
        default=None,
        metavar="PATH",
        help="MBM problems folder, folder with problems.tar.bz2, or the archive (default: "
        f"${mbm.ENV_VAR}, else the cache, else downloaded once with pip into the cache)",
    )
    parser.add_argument(
        "--robot",
        default="panda",
        metavar="NAME|FILE",
        help="the robot: a shipped one (panda, ur5, fetch, baxter: its MBM set is fetched like "
        "the Panda's), a robot description YAML or a *_moveit_config folder (give its problems "
        "with --dataset, or --random)",
    )
    parser.add_argument(
        "--families",
        nargs="+",
        metavar="FAMILY",
        help="families to run (default: every family of the set; a folder of saved random "
        f"problems: {RANDOM_FAMILY})",
    )
    parser.add_argument("--limit", type=cli.positive_int, help="first N problems per family")
    parser.add_argument(
        "--random",
        type=cli.positive_int,
        metavar="N",
        help="make N random problems (obstacles around the arm) instead of loading MBM sets",
    )
    parser.add_argument(
        "--seed", type=cli.non_negative_int, default=0, help="seed of --random (default 0)"
    )
    parser.add_argument(
        "--save-problems",
        type=cli.output_dir("problems folder"),
        metavar="DIR",
        help=f"write the random problems into DIR/{RANDOM_FAMILY}/ (sceneNNNN.yaml, "
        "requestNNNN.yaml; --dataset DIR runs them again)",
    )
    parser.add_argument("--timeout", type=cli.positive_float, default=5.0, help="s per problem")
    parser.add_argument(
        "--report", type=cli.output_file("report"), help="JSON report, one row each"
    )
    parser.add_argument(
        "--options", type=cli.input_file("options file"), help="planner options YAML"
    )
    parser.add_argument(
        "--compare-ompl", action="store_true", help="also run OMPL RRTConnect+simplify"
    )
    parser.add_argument(
        "--profile", action="store_true", help="print where the time of the requests goes"
    )
    parser.add_argument(
        "--plot",
        type=cli.output_file("plot"),
        help="PNG with histograms of the times (matplotlib)",
    )
    args = parser.parse_args(argv)
    if args.compare_ompl and not ompl_available():
        raise ConfigError("--compare-ompl needs the ompl package (pip install ompl)")
    try:
        args.options = load_planner_options(args.options) if args.options else None
    except (FileNotFoundError, RuntimeError, ValueError) as e:
        raise ConfigError(str(e).splitlines()[0]) from None
    if args.random is not None:
        _check_random_args(args)
        return args
    if args.save_problems is not None:
        raise ConfigError("--save-problems saves the problems of --random: give --random N")
    shipped = args.robot in mbm.ARCHIVE_SHA256
    if args.dataset is None and not shipped:
        raise ConfigError(
            f"--robot {args.robot}: no MotionBenchMaker set ships for it: give its problems "
            "with --dataset, or make some with --random N"
        )
    try:
        args.dataset = mbm.find_problems(args.dataset, robot=args.robot if shipped else "panda")
    except (FileNotFoundError, RuntimeError, ValueError) as e:
        raise ConfigError(str(e).splitlines()[0]) from None
    if args.families is None:  # a folder of saved random problems runs as it is
        found = mbm.families_in(args.dataset)
        others = [f for f in found if f != RANDOM_FAMILY]
        args.families = others or found
    missing = [f for f in args.families if not (args.dataset / f).is_dir()]
    if missing:
        raise ConfigError(f"{args.dataset}: no MBM family {', '.join(missing)}")
    return args


def _check_random_args(args) -> None:
    """--random makes its own problems: the options that choose MBM problems do not go with
    it, and a folder to save into must not hold problems already."""
    given = [
        name
        for name, value in (
            ("--dataset", args.dataset),
            ("--families", args.families),
            ("--limit", args.limit),
        )
        if value is not None
    ]
    if given:
        raise ConfigError(f"--random makes its own problems: {given[0]} does not go with it")
    if args.save_problems is not None:
        folder = args.save_problems / RANDOM_FAMILY
        if next(folder.glob("*.yaml"), None) is not None:
            raise ConfigError(f"{folder} holds problems already: give a new or empty folder")
    args.families = [RANDOM_FAMILY]


def make_random_problems(scene, count: int, seed: int, folder: Path) -> list:
    """Draws ``count`` random problems for the scene's robot and writes them into
    ``folder/random/`` (``planning.io.problem_files``); returns, in order, an ``MbmProblem``
    for each problem made and the ``ProblemGenerationError`` of each that could not be."""
    result = []
    workspace = workspace_of(scene)  # the robot's part: its scene, and where it reaches
    for problem in random_problems(scene, count, seed, workspace):
        if isinstance(problem, Exception):
            result.append(problem)
            continue
        start = dict(zip(problem.joint_names, problem.q_start, strict=True))
        goal = dict(zip(problem.joint_names, problem.q_goal, strict=True))
        scene_file, request_file = problem_files.write_problem(
            folder,
            RANDOM_FAMILY,
            problem.number,
            problem_files.scene_message(problem.objects, f"random{problem.number:04d}"),
            problem_files.request_message(workspace.group, start | problem.other_joints, goal),
        )
        result.append(mbm.MbmProblem(RANDOM_FAMILY, problem.number, scene_file, request_file))
    return result


def _unmade_row(error) -> dict:
    row = {"family": RANDOM_FAMILY, "problem": error.number, "valid": False, "success": False}
    row.update(time_s=None, path_length=None, path_valid_fine=None, path=None)
    row["error"] = str(error)
    return row


def main(argv=None) -> int:
    """Runs the benchmark; returns the exit code (``drake_sim.base.cli.run``: 2 with one stderr
    line on bad input, 0 on Ctrl-C or SIGTERM). MBM scenes name joints and allowed pairs the
    robot's URDF lacks (VAMP's models fix the grippers): their warnings, one per scene, would
    bury the table, so ``planning.io`` logs errors only while it runs."""
    with cli.logger_level("planning.io", logging.ERROR):
        return cli.run(_main, argv)


def _main(argv) -> int:
    args = _parse_args(argv)
    folder = args.dataset
    options = args.options or MotionPlannerOptions()
    if args.compare_ompl:
        from ompl import util as ou

        ou.setLogLevel(ou.LogLevel.LOG_WARN)
    # The compiled planner from the first problem: a fresh install waits for its build here.
    planner_kernels.wait_ready(progress=planner_kernels.ProgressLine("planning.benchmark"))
    scene = PlanningScene(robot_config(args.robot))
    planner = MotionPlanner(scene, options)
    joint_names = list(group_joint_names(scene))
    with contextlib.ExitStack() as stack:
        if args.random is None:
            problems = list(mbm.iter_problems(folder, args.families, args.limit))
        else:
            folder = args.save_problems or Path(
                stack.enter_context(tempfile.TemporaryDirectory(prefix="plan_benchmark-"))
            )
            problems = make_random_problems(scene, args.random, args.seed, folder)
        rows, profiler = _run(args, scene, planner, problems)
    for row in rows:
        row["joint_names"] = joint_names
    print(summarize(rows))
    if profiler is not None:
        print("\n" + breakdown(profiler.requests))
    if args.report is not None:
        cli.write_text(args.report, json.dumps(rows, indent=1), "report")
    if args.plot is not None:
        args.plot.parent.mkdir(parents=True, exist_ok=True)
        plot_times(rows, args.plot)
    return 0


def _run(args, scene, planner, problems: list):
    """Plans the problems (an exception in the list: a random problem that could not be
    made), then OMPL's with ``--compare-ompl``; returns the rows and the profiler (or None)."""
    made = [p for p in problems if not isinstance(p, Exception)]
    bar = _progress(len(problems) + (len(made) if args.compare_ompl else 0))
    profiler = PhaseProfiler() if args.profile else None
    rows = []
    with profiler or contextlib.nullcontext():  # wraps the planner's steps while profiling
        for problem in problems:
            if isinstance(problem, Exception):
                rows.append(_unmade_row(problem))
            else:
                rows.append(run_problem(scene, planner, problem, args.timeout, profiler))
            row = rows[-1]
            bar.write(
                f"{row['family']} {row['problem']:4d} valid={row['valid']} "
                f"success={row['success']} t={row['time_s'] or 0:.3f}s {row.get('error', '')}"
            )
            bar.update()
    if args.compare_ompl:
        # After all of ours: running OMPL in between was measured to slow our planner 2-3x.
        for problem, row in zip(problems, rows, strict=True):
            if isinstance(problem, Exception):
                continue
            if row["valid"]:
                run_ompl(scene, problem, row, args.timeout)
            bar.update()
    bar.close()
    return rows, profiler


class _PlainProgress:
    """Stands in for a tqdm bar when tqdm is not installed: prints lines, counts nothing."""

    def write(self, line: str) -> None:
        print(line, flush=True)

    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass


def _progress(total: int):
    """A tqdm progress bar on stderr (its lines on stdout), or plain printing without tqdm."""
    try:
        from tqdm import tqdm
    except ImportError:
        return _PlainProgress()

    class _Bar(tqdm):
        def write(self, line: str) -> None:  # tqdm.write keeps the bar below the lines
            tqdm.write(line, file=sys.stdout)

    return _Bar(total=total, file=sys.stderr, unit="problem", dynamic_ncols=True, disable=None)


def plot_times(rows: list[dict], filename: Path) -> None:
    """Writes a PNG with histograms of the time per valid problem, ours and OMPL's (when in
    the rows), on a log time axis; unsolved problems count at their time (the timeout)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    series = {"ours": [r["time_s"] for r in rows if r["valid"] and r["time_s"]]}
    ompl = [r["ompl_time_s"] for r in rows if r["valid"] and r.get("ompl_time_s")]
    if ompl:
        series["OMPL RRTConnect + simplify"] = ompl
    every = [t for times in series.values() for t in times]
    fig, ax = plt.subplots(figsize=(7, 4))
    if every:
        bins = np.geomspace(min(every) * 0.9, max(every) * 1.1, 30)
        for label, times in series.items():
            solved = "success" if label == "ours" else "ompl_success"
            count = sum(bool(r.get(solved)) for r in rows if r["valid"])
            ax.hist(
                times,
                bins=bins,
                alpha=0.6,
                label=f"{label}: median {np.median(times) * 1e3:.0f} ms, "
                f"solved {count}/{len(times)}",
            )
    ax.set_xscale("log")
    ax.set_xlabel("time per problem, s (log scale)")
    ax.set_ylabel("problems")
    families = sorted({r.get("family", "") for r in rows})
    random = families == ["random"]
    ax.set_title("random Panda problems" if random else "MotionBenchMaker Panda problems")
    ax.legend()
    fig.tight_layout()
    fig.savefig(filename, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())  # main runs under drake_sim.base.cli.run
