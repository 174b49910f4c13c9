"""``python -m drake_sim.tools.slam_relations TRAJ.txt RELATIONS``: a SLAM trajectory scored
against ground-truth relations, as Kümmerle et al. 2009 ("On measuring the accuracy of SLAM
algorithms") score GMapping, graph mapping and since then Cartographer.

A relations file has one relation per line, ``t_i t_j x y z roll pitch yaw``: the true pose of
the robot at time ``t_j`` seen from the robot at ``t_i`` (only x, y and yaw are used: the
logs are planar). For an estimated trajectory (TUM format, as ``drake_sim.mapping --log
--trajectory`` writes it) each relation gives ``d_ij = x_i^-1 (+) x_j`` and the error
``e_ij = d*_ij^-1 (+) d_ij``; the score is the mean and standard deviation over the relations
of ``|trans(e)|`` (m) and ``|rot(e)|`` (degrees), and of their squares. A relation whose times
are not in the trajectory (within ``TIME_TOLERANCE``) is left out and counted as missing.
Exit codes: 0, 2 for bad input (one line on stderr).
"""

import dataclasses as dc
import json
import math
import sys
from pathlib import Path

import numpy as np

from drake_sim.base import cli
from drake_sim.base.errors import ConfigError
from drake_sim.base.planar import relative_pose, wrap_angle

TIME_TOLERANCE = 5e-5
"""s: a relation's time matches a trajectory's pose this close (some scans of the Intel log
are less than a millisecond apart)."""


@dc.dataclass(frozen=True)
class RelationScore:
    """Kümmerle's metric over the relations found in a trajectory (m, m^2, deg, deg^2)."""

    relations: int
    missing: int
    trans_mean_m: float
    trans_std_m: float
    trans2_mean_m2: float
    trans2_std_m2: float
    rot_mean_deg: float
    rot_std_deg: float
    rot2_mean_deg2: float
    rot2_std_deg2: float


def load_relations(path: Path | str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t_i (n,), t_j (n,), d* (n, 3) as [x, y, yaw]) of a relations file.

    Raises:
        ConfigError: a line that does not hold 8 finite numbers (file and line named), or
            no relation at all.
    """
    data = _rows(path, "a relation is 8 numbers, t_i t_j x y z r p yaw", "relations")
    return data[:, 0], data[:, 1], data[:, [2, 3, 7]]


def load_tum(path: Path | str) -> tuple[np.ndarray, np.ndarray]:
    """(times (n,), poses (n, 3) [x, y, yaw]) of a TUM trajectory (yaw about z).

    Raises:
        ConfigError: a line that does not hold 8 finite numbers, or no pose at all.
    """
    d = _rows(path, "a TUM pose is 8 numbers, t x y z qx qy qz qw", "poses")
    qx, qy, qz, qw = d[:, 4], d[:, 5], d[:, 6], d[:, 7]
    yaw = np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
    return d[:, 0], np.stack([d[:, 1], d[:, 2], yaw], -1)


def _rows(path: Path | str, shape: str, what: str) -> np.ndarray:
    """(n, 8) numbers of a text file of 8 numbers a line (blank and ``#`` lines skipped)."""
    try:
        lines = Path(path).read_text().splitlines()
    except (OSError, UnicodeDecodeError) as e:
        raise ConfigError(f"{path}: cannot be read ({e})") from None
    rows = []
    for number, line in enumerate(lines, 1):
        fields = line.split()
        if not fields or fields[0].startswith("#"):
            continue
        try:
            values = [float(v) for v in fields]
        except ValueError:
            values = []
        if len(values) != 8 or not all(math.isfinite(v) for v in values):
            raise ConfigError(f"{path}:{number}: {shape}")
        rows.append(values)
    if not rows:
        raise ConfigError(f"{path}: no {what}")
    return np.array(rows)


def score(times, poses, relations) -> RelationScore:
    """Kümmerle's metric of the trajectory ``(times, poses)`` on ``relations`` (``load_relations``'
    triple); relations with a time not in ``times`` are counted as missing."""
    times = np.asarray(times, dtype=float)
    poses = np.asarray(poses, dtype=float).reshape(-1, 3)
    t_i, t_j, truth = relations
    i, found_i = _find(times, t_i)
    j, found_j = _find(times, t_j)
    ok = found_i & found_j
    if not ok.any():
        nan = math.nan
        return RelationScore(0, len(t_i), *([nan] * 8))
    estimate = relative_pose(poses[i[ok]], poses[j[ok]])
    error = relative_pose(truth[ok], estimate)
    trans = np.hypot(error[:, 0], error[:, 1])
    rot = np.degrees(np.abs(wrap_angle(error[:, 2])))
    return RelationScore(
        int(ok.sum()),
        int((~ok).sum()),
        float(trans.mean()),
        float(trans.std()),
        float((trans**2).mean()),
        float((trans**2).std()),
        float(rot.mean()),
        float(rot.std()),
        float((rot**2).mean()),
        float((rot**2).std()),
    )


def _find(times: np.ndarray, wanted: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(index into ``times`` of each wanted time's nearest, whether within TIME_TOLERANCE)."""
    order = np.argsort(times, kind="stable")
    ordered = times[order]
    k = np.searchsorted(ordered, wanted)
    below, above = np.clip(k - 1, 0, len(ordered) - 1), np.clip(k, 0, len(ordered) - 1)
    nearer = np.abs(wanted - ordered[below]) <= np.abs(wanted - ordered[above])
    index = order[np.where(nearer, below, above)]
    return index, np.abs(times[index] - wanted) <= TIME_TOLERANCE


def main(argv=None) -> int:
    p = cli.ArgumentParser(
        prog="python -m drake_sim.tools.slam_relations", description=__doc__.split("\n")[0]
    )
    p.add_argument("trajectory", type=cli.input_file("trajectory"), help="TUM trajectory")
    p.add_argument("relations", type=cli.input_file("relations"), help="relations file")
    p.add_argument("--json", type=cli.output_file("score"), help="write the score here")
    args = p.parse_args(argv)
    result = score(*load_tum(args.trajectory), load_relations(args.relations))
    print(
        f"{result.relations} relations ({result.missing} missing): translation "
        f"{result.trans_mean_m:.3f} +- {result.trans_std_m:.3f} m, rotation "
        f"{result.rot_mean_deg:.2f} +- {result.rot_std_deg:.2f} deg"
    )
    if args.json:
        cli.write_text(args.json, json.dumps(dc.asdict(result), indent=2) + "\n", "score")
    return cli.EXIT_OK


if __name__ == "__main__":
    sys.exit(cli.run(main))
