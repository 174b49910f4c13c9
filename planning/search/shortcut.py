"""Path shortcutting: greedy vertex skipping, then random shortcuts checked in batches.

References:
    R. Geraerts, M. Overmars, "Creating high-quality paths for motion planning", IJRR 2007
    (random shortcutting).
"""

from __future__ import annotations

import time

import numpy as np

from planning.paths import drop_duplicates


def shortcut(
    adapter,
    path: np.ndarray,
    *,
    iterations: int,
    deadline: float,
    rng: np.random.Generator,
    batch: int = 8,
) -> np.ndarray:
    """Shortens a collision-free path: greedy vertex skipping, then random shortcuts.

    The greedy pass joins each waypoint to the farthest later waypoint it sees in a straight
    line (all candidates of a waypoint in one query); the random pass draws ``batch`` pairs of
    points along the path (by arc length) at a time, checks their straight segments in one
    query, and replaces the parts between them by the collision-free segments, largest
    shortening first, as long as the replaced parts do not overlap.

    Returns:
        the shorter path (the input when nothing helped), same ends.
    """
    path = _greedy(adapter, path, deadline)
    for _ in range(int(np.ceil(iterations / batch))):
        if len(path) < 3 or time.perf_counter() > deadline:
            break
        cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
        s = np.sort(rng.uniform(0.0, cum[-1], (batch, 2)), axis=1)
        seg = np.clip(np.searchsorted(cum, s, "right") - 1, 0, len(path) - 2)
        keep = seg[:, 0] < seg[:, 1]
        if not keep.any():
            continue
        s, seg = s[keep], seg[keep]
        q = [_points(path, cum, seg[:, k], s[:, k]) for k in (0, 1)]
        gain = (s[:, 1] - s[:, 0]) - np.linalg.norm(q[1] - q[0], axis=1)
        free = (adapter.free_prefixes(q[0], q[1]) >= 1.0) & adapter.configs_free(q[0])
        chosen: list[int] = []
        for k in np.argsort(-gain):
            apart = all(s[k, 1] <= s[c, 0] or s[k, 0] >= s[c, 1] for c in chosen)
            if free[k] and gain[k] > 1e-9 and apart:
                chosen.append(int(k))
        if chosen:
            path = _splice(path, cum, [(s[k], q[0][k], q[1][k]) for k in chosen])
    return _greedy(adapter, path, deadline)


def _points(path, cum, i, s) -> np.ndarray:
    """Points at arc lengths s on segments i (arrays), (K, 7)."""
    length = cum[i + 1] - cum[i]
    t = np.where(length > 0, (s - cum[i]) / np.where(length > 0, length, 1.0), 0.0)
    return path[i] + t[:, None] * (path[i + 1] - path[i])


def _splice(path, cum, cuts) -> np.ndarray:
    """Replaces the parts of the path between arc lengths (s_a, s_b) by straight segments
    q_a -> q_b, for non-overlapping cuts [((s_a, s_b), q_a, q_b), ...]."""
    out, done = [], -1.0
    for (s_a, s_b), q_a, q_b in sorted(cuts, key=lambda c: c[0][0]):
        out.extend(path[(cum > done) & (cum < s_a)])
        out.extend([q_a, q_b])
        done = s_b
    out.extend(path[cum > done])
    out = [path[0], *out] if done < 0 or not np.allclose(out[0], path[0]) else out
    return drop_duplicates(np.asarray(out))


def _greedy(adapter, path: np.ndarray, deadline: float) -> np.ndarray:
    out, i = [path[0]], 0
    while i < len(path) - 1:
        j = i + 1
        if j < len(path) - 1 and time.perf_counter() <= deadline:
            later = np.arange(i + 2, len(path))
            starts = np.repeat(path[i][None, :], len(later), axis=0)
            free = np.flatnonzero(adapter.free_prefixes(starts, path[later]) >= 1.0)
            if len(free):
                j = int(later[free[-1]])
        out.append(path[j])
        i = j
    return np.asarray(out)
