"""Piecewise-linear joint-space paths: arrays of shape (N, 7), arm joint waypoints (rad) whose
straight-line interpolation is the path."""

from __future__ import annotations

import numpy as np


def densify(path: np.ndarray, resolution: float) -> tuple[np.ndarray, np.ndarray]:
    """Interpolates a path so that consecutive configurations are at most ``resolution`` apart.

    Args:
        path: (N, 7) waypoints, rad.
        resolution: largest joint-space L2 distance between consecutive samples, rad.

    Returns:
        (samples, segment): the samples (M, 7), first and last waypoints included, and the index
        of the path segment each sample lies on.
    """
    path = np.asarray(path)
    steps = np.diff(path, axis=0)
    ratio = np.linalg.norm(steps, axis=1) / resolution
    if not np.all(np.isfinite(ratio)):
        raise ValueError("cannot densify a path with non-finite waypoints")
    n = np.maximum(1, np.ceil(ratio).astype(np.int64))  # samples per segment, its end included
    segment = np.repeat(np.arange(len(n)), n)
    k = np.arange(1, len(segment) + 1) - np.repeat(np.cumsum(n) - n, n)  # 1..n per segment
    samples = path[segment] + (k / n[segment])[:, None] * steps[segment]
    return np.vstack([path[:1], samples]), np.concatenate([[0], segment])


def path_length(path: np.ndarray) -> float:
    """Joint-space L2 length of a piecewise-linear path, rad."""
    return float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum()) if len(path) > 1 else 0.0


def drop_duplicates(path: np.ndarray, tolerance: float = 1e-12) -> np.ndarray:
    """Drops waypoints within ``tolerance`` rad of their predecessor."""
    keep = np.concatenate([[True], np.linalg.norm(np.diff(path, axis=0), axis=1) > tolerance])
    return path[keep]
