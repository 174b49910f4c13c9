"""Where the time of a request goes: ``python -m planning.benchmark --profile``.

``PhaseProfiler`` wraps, inside its ``with`` block only, the functions a request goes through
(monkeypatching: the planner's code is untouched and costs nothing when not profiling) and charges
every moment to one row: the innermost *stage* (a step of ``MotionPlanner.plan_path``, below) and
what ran there, the stage's own Python code (``python``), the compiled sphere kernel (``spheres``:
``SphereCollisionModel.classify``/``prefixes``; in the compiled search, ``search on spheres`` and
``fine check on spheres``: ``planning.search.compiled_rrt``) or Drake's collision checker
(``drake``: ``CollisionChecker.Check*CollisionFree``, the fallback for what the spheres cannot
decide). The times are exclusive, so a request's rows sum to the time inside ``plan_path``; ``take``
adds an ``other`` row for the rest of the benchmark's timed interval. Stages nest: ``validate 0.01
rad > rrt-connect`` is a repair of a segment that failed the fine check (the ``request`` and
``find`` ancestors are left out of the row names). Each wrapped call costs about a microsecond,
which lands in the enclosing row. A normal run checks the ends, searches and fine-checks in one
compiled call (``compiled_rrt.solve``); the profiler has ``JointPathSearch`` make them separate
calls (``fused`` False), so that each is timed, which costs their dispatches (~0.1 ms a request,
most of it in the first call after a scene's set-up).
"""

from __future__ import annotations

import functools
import time
from collections import defaultdict

import numpy as np
from pydrake.planning import CollisionChecker

from planning.collision.spheres import SphereCollisionModel
from planning.motion_planner import MotionPlanner
from planning.search import compiled_rrt, kto
from planning.search.joint_path import JointPathSearch

# (owner, method, stage): the steps of a request, each named after what its code does.
STAGES = (
    (MotionPlanner, "plan_path", "request"),  # argument conversion, then the steps below
    (MotionPlanner, "_check_start", "start/goal check"),
    (MotionPlanner, "_check_ends", "start/goal check"),  # Drake, for what the spheres cannot
    (JointPathSearch, "proves_free", "start/goal check"),  # the spheres
    (MotionPlanner, "_make_plan", "retime"),  # plan_to_joints only: Plan + smoothing check
    (JointPathSearch, "find", "find: straight line, adapters"),  # and the steps below
    (JointPathSearch, "_compiled", "compiled"),  # the compiled search and its fine check
    (JointPathSearch, "_rrt", "rrt-connect"),  # tree growth on coarse (0.1 rad) edges
    (JointPathSearch, "_shortcut", "shortcut"),
    (JointPathSearch, "_validated", "validate 0.01 rad"),  # fine re-check, repairs nested
    (kto, "kto_shorter", "kto"),  # looked up when called: the wrapper is seen
)
# (owner, method, kind): the collision checks, charged to the stage that called them.
CHECKS = (
    (SphereCollisionModel, "classify", "spheres"),
    (SphereCollisionModel, "prefixes", "spheres"),
    (SphereCollisionModel, "sync", "sphere sync"),
    (compiled_rrt, "plan", "search on spheres"),  # straight line, RRT-Connect, shortcuts
    (compiled_rrt, "fine_check", "fine check on spheres"),
    (CollisionChecker, "CheckConfigCollisionFree", "drake"),
    (CollisionChecker, "CheckConfigsCollisionFree", "drake"),
    (CollisionChecker, "CheckEdgeCollisionFree", "drake"),
)
OTHER = "other (benchmark's timer outside plan_path)"
_UNSHOWN = ("request", "find: straight line, adapters")  # ancestors left out of row names


class PhaseProfiler:
    """Exclusive time per (stage, kind) row and check counts, request by request.

    Use as ``with PhaseProfiler() as profiler:``, then ``profiler.take(total_s)`` after each
    request. ``self.requests`` holds what ``take`` returned.
    """

    def __init__(self):
        self.requests: list[dict] = []
        self._stack: list[list] = []  # frames: [row, stage path, start s, children s]
        self._times: dict[str, float] = defaultdict(float)
        self._calls: dict[str, int] = defaultdict(int)
        self._saved: list[tuple] = []

    def __enter__(self) -> PhaseProfiler:
        # The compiled search's steps as separate calls, so that each is timed (their
        # dispatches cost ~0.1 ms a request more than the one call of a normal run).
        self._saved.append((JointPathSearch, "fused", JointPathSearch.__dict__["fused"]))
        JointPathSearch.fused = False
        for owner, name, stage in STAGES:
            self._wrap(owner, name, stage, is_stage=True)
        for owner, name, kind in CHECKS:
            self._wrap(owner, name, kind, is_stage=False)
        return self

    def __exit__(self, *exc) -> None:
        for owner, name, original in reversed(self._saved):
            setattr(owner, name, original)
        self._saved.clear()

    def _wrap(self, owner, name: str, label: str, *, is_stage: bool) -> None:
        original = owner.__dict__[name]
        self._saved.append((owner, name, original))
        counter = f"{owner.__name__.rsplit('.', 1)[-1]}.{name}"

        @functools.wraps(original)
        def wrapper(*args, **kwargs):
            if not (is_stage or self._stack):  # a check outside any request: not profiled
                return original(*args, **kwargs)
            parent = self._stack[-1][1] if self._stack else ()
            path = (*parent, label) if is_stage else parent
            shown = [p for p in path[:-1] if p not in _UNSHOWN] + list(path[-1:])
            row = " > ".join(shown) + (": python" if is_stage else f": {label}")
            if not is_stage:
                self._calls[counter] += 1
                if name == "CheckConfigsCollisionFree":
                    self._calls["Drake configurations"] += len(args[1])
                elif name == "CheckConfigCollisionFree":
                    self._calls["Drake configurations"] += 1
            self._stack.append([row, path, time.perf_counter(), 0.0])
            try:
                result = original(*args, **kwargs)
                if owner is compiled_rrt:  # plan and fine_check return their count last
                    self._calls["compiled configurations"] += int(result[-1])
                return result
            finally:
                row, _, start, children = self._stack.pop()
                elapsed = time.perf_counter() - start
                self._times[row] += elapsed - children
                if self._stack:
                    self._stack[-1][3] += elapsed

        setattr(owner, name, wrapper)

    def take(self, total_s: float | None = None, name: str = "") -> dict:
        """Returns and records the rows (s) and counts since the last ``take``; with the
        request's measured ``total_s``, also ``other`` (the part outside the wrapped calls) and
        ``total``. Rows under a ``retime`` root are reported apart (not part of ``total``)."""
        times, calls = dict(self._times), dict(self._calls)
        self._times.clear()
        self._calls.clear()
        if total_s is not None:
            inside = sum(t for row, t in times.items() if not row.startswith("retime"))
            times[OTHER] = total_s - inside
            times["total"] = total_s
        record = {"name": name, "times": times, "calls": calls}
        self.requests.append(record)
        return record


def _group_rows(records: list[dict]) -> list[str]:
    """The rows seen in any record, the costliest first (``total`` last)."""
    sums: dict[str, float] = defaultdict(float)
    for record in records:
        for row, t in record["times"].items():
            sums[row] += t
    sums.pop("total", None)
    return sorted(sums, key=lambda row: (row.startswith("retime"), -sums[row]))


def breakdown(records: list[dict]) -> str:
    """Returns the tables of ``--profile`` over the timed requests in ``records``.

    Columns, per row over all requests: the median, 95th percentile and maximum of its ms per
    request;
    ``% mid``, its share of the summed time of the middle requests (total between the 40th and
    60th percentile of the totals); ``% tail``, its share of the summed time of the tail
    requests (total at or above the 95th percentile). Shares are time-weighted, so each column
    sums to 100 % with ``other``. Then the same for the tail requests alone, and the checks
    per request.
    """
    records = [r for r in records if "total" in r["times"]]
    if not records:
        return "profile: no timed request"
    totals = np.array([r["times"]["total"] for r in records])
    lo, hi, p95 = np.percentile(totals, [40, 60, 95])
    mid = [r for r, t in zip(records, totals, strict=True) if lo <= t <= hi]
    tail = [r for r, t in zip(records, totals, strict=True) if t >= p95]
    lines = [
        f"profile over {len(records)} requests: ms per request (exclusive), shares of the "
        f"summed time of the {len(mid)} middle (40th-60th pct) and {len(tail)} tail "
        f"(>= p95, {p95 * 1e3:.1f} ms) requests",
        _table(records, {"% mid": mid, "% tail": tail}),
        "",
        f"tail only ({len(tail)} requests: "
        + ", ".join(f"{r.get('name', '?')} {r['times']['total'] * 1e3:.0f} ms" for r in tail)
        + ")",
        _table(tail, {"% tail": tail}),
        "",
        _calls_table(records, tail),
    ]
    return "\n".join(lines)


def _ms(records: list[dict], row: str) -> np.ndarray:
    return np.array([r["times"].get(row, 0.0) * 1e3 for r in records])


def _table(records: list[dict], shares: dict[str, list[dict]]) -> str:
    head = f"{'phase':46s} {'med ms':>8s} {'p95 ms':>8s} {'max ms':>8s}"
    head += "".join(f" {s:>7s}" for s in shares)
    lines = [head, "-" * len(head)]
    rows = _group_rows(records)
    timed = [row for row in rows if not row.startswith("retime")]
    apart = [row for row in rows if row.startswith("retime")]
    for row in [*timed, "total", *apart]:
        ms = _ms(records, row)
        line = f"{row[:46]:46s} {np.median(ms):8.2f} {np.percentile(ms, 95):8.2f} {ms.max():8.2f}"
        for group in shares.values():
            whole = _ms(group, "total").sum()
            if whole and row in timed + ["total"]:
                line += f" {100 * _ms(group, row).sum() / whole:6.1f}%"
            else:
                line += f" {'-':>7s}"
        lines.append(line)
        if row == "total" and apart:
            lines.append("not in total: plan_to_joints' time parametrisation, after plan_path:")
    return "\n".join(lines)


def _calls_table(records: list[dict], tail: list[dict]) -> str:
    names = sorted({name for r in records for name in r["calls"]})
    head = f"{'checks per request':46s} {'median':>8s} {'p95':>8s} {'tail med':>8s}"
    lines = [head, "-" * len(head)]
    for name in names:
        every = [r["calls"].get(name, 0) for r in records]
        in_tail = [r["calls"].get(name, 0) for r in tail]
        lines.append(
            f"{name:46s} {np.median(every):8.0f} {np.percentile(every, 95):8.0f} "
            f"{np.median(in_tail):8.0f}"
        )
    return "\n".join(lines)
