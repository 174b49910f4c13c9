"""The command line of ``python -m drake_sim.sweep`` (see the package docstring)."""

import json
import os
from pathlib import Path

from drake_sim.base import cli
from drake_sim.base.errors import ConfigError
from drake_sim.sweep.backends import BACKENDS, check_backend, make_backend
from drake_sim.sweep.execute import execute, header, write_sweep_info
from drake_sim.sweep.jobs import make_job
from drake_sim.sweep.plot import plot_sweep
from drake_sim.sweep.spec import load_sweep, rollouts
from drake_sim.sweep.summary import format_summary, summarize
from drake_sim.sweep.table import TABLE_FILE, Table, read_rows

PROG = "python -m drake_sim.sweep"
DEFAULT_OUT = Path("sweeps")  # The table goes to sweeps/<sweep name>/ unless --out says.


def _parse_args(argv):
    parser = cli.ArgumentParser(
        prog=PROG, description="Run a parameter sweep or Monte-Carlo study."
    )
    parser.add_argument("sweep", nargs="?", type=cli.input_file("sweep file"), help="sweep YAML")
    parser.add_argument("--backend", choices=BACKENDS, default="local", help="default: local")
    parser.add_argument("--address", help="Ray cluster address ('auto' joins the running one)")
    parser.add_argument(
        "--workers", type=cli.positive_int, help="worker processes (default: the CPU count)"
    )
    parser.add_argument(
        "--out", type=cli.output_dir("output folder"), help="default: sweeps/<sweep name>/"
    )
    parser.add_argument(
        "--resume", action="store_true", help="skip the rollouts already in the table"
    )
    parser.add_argument("--limit", type=cli.positive_int, help="only the first N rollouts")
    parser.add_argument(
        "--plot", type=cli.input_path("sweep folder"), metavar="DIR", help="write PNGs of DIR"
    )
    args = parser.parse_args(argv)
    if (args.sweep is None) == (args.plot is None):
        raise ConfigError(f"{PROG}: give a sweep file, or --plot DIR (see --help)")
    if args.address is not None and args.backend != "ray":
        raise ConfigError("--address is for --backend ray")
    if args.plot is not None and not args.plot.is_dir():
        raise ConfigError(f"--plot: not a folder: {args.plot}")
    return args


def main(argv=None) -> int:
    args = _parse_args(argv)
    if args.plot is not None:
        for path in plot_sweep(args.plot):
            print(f"wrote {path}")
        return cli.EXIT_OK
    check_backend(args.backend)  # a missing Ray fails here, before anything is written
    spec = load_sweep(args.sweep)
    job = make_job(spec)  # checks runner, options, paths and metrics before anything runs
    out = args.out if args.out is not None else DEFAULT_OUT / spec.name
    every = rollouts(spec)[: args.limit]
    table = Table(out / TABLE_FILE, header(spec), resume=args.resume)  # written with its rows
    todo = [r for r in every if r.index not in table.done]
    workers = args.workers or os.cpu_count() or 1
    # Started (or joined, for Ray) before the plan is printed: a failure is one line, no files.
    backend = make_backend(args.backend, workers=workers, address=args.address) if todo else None
    try:
        write_sweep_info(spec, out)
        print(
            f"{spec.name}: {len(todo)} of {len(every)} rollouts to run ({spec.runner}, "
            f"{args.backend} backend, {workers} worker{'s' if workers > 1 else ''}) "
            f"-> {table.path}",
            flush=True,
        )
        finished = execute(spec, job, todo, table, backend) if backend is not None else True
    finally:
        if backend is not None:
            backend.close()
        table.close()
    _, rows = read_rows(table.path)
    wanted = {r.index for r in every}
    rows = [r for r in rows if r["index"] in wanted]
    summary = summarize(rows, spec.metrics, has_success=bool(spec.success))
    if not finished:
        print(f"stopped: {len(rows)} of {len(every)} rollouts in {table.path} (--resume continues)")
        return cli.EXIT_OK
    print(format_summary(summary))
    cli.write_text(out / "summary.json", json.dumps(summary, indent=2) + "\n", "summary")
    return cli.EXIT_OK
