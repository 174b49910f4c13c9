"""Running a sweep: the rollouts not yet in the table go to the backend, and each result becomes
a table row (parameters, seed, kept metrics, success, status, wall time, worker) saved the
moment it arrives. A user stop (Ctrl-C, SIGTERM) cancels what has not started and keeps every
row already saved, and the one being saved when the stop came.
"""

import dataclasses as dc
import json
from pathlib import Path

from tqdm import tqdm

from drake_sim.base import cli
from drake_sim.sweep.spec import Rollout, SweepSpec
from drake_sim.sweep.table import Table, columns

SWEEP_FILE = "sweep.json"  # What --plot needs to know about the sweep, next to the table.


def header(spec: SweepSpec) -> list[str]:
    return columns([p.path for p in spec.parameters], spec.metrics)


def make_row(spec: SweepSpec, result: dict) -> dict:
    """A table row from a worker's result (``runners.run_rollout``)."""
    report = result["report"]
    row = {key: result[key] for key in ("index", "status", "seed", "wall_time_s", "worker")}
    row["reason"] = result["reason"]
    row.update(result["overrides"])
    row.update({key: report.get(key) for key in spec.metrics})
    if spec.success:
        row["success"] = result["status"] == "ok" and all(c.holds(report) for c in spec.success)
    return row


def write_sweep_info(spec: SweepSpec, out: Path) -> None:
    """Writes ``sweep.json``: the sweep's name, runner, parameters, metrics and success test."""
    info = {
        "name": spec.name,
        "runner": spec.runner,
        "source": spec.source,
        "size": spec.size,
        "parameters": [dc.asdict(p) for p in spec.parameters],
        "metrics": list(spec.metrics),
        "success": [dc.asdict(c) for c in spec.success],
    }
    cli.write_text(out / SWEEP_FILE, json.dumps(info, indent=2) + "\n", "sweep info")


def execute(spec: SweepSpec, job: dict, todo: list[Rollout], table: Table, backend) -> bool:
    """Runs ``todo`` on ``backend``, saving each row in ``table`` as it arrives.

    Returns:
        True if every rollout ran, False if a user stop ended the sweep early (the rows that
        finished are in the table either way).
    """
    plain = [dc.asdict(r) for r in todo]
    arrived = None  # A result whose row a stop may have cut off while it was being saved.
    with tqdm(total=len(todo), unit="rollout", disable=None, leave=False) as bar:
        try:
            for arrived in backend.run(job, plain):
                table.append(make_row(spec, arrived))
                bar.update()
        except BaseException as e:  # a stop may surface as another error: see cli.is_stop
            if not cli.is_stop(e):
                raise
            for result in [arrived, *backend.stop()]:
                if result is not None and result["index"] not in table.done:
                    table.append(make_row(spec, result))
            return False
    return True
