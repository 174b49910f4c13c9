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
    samples, segment = [path[:1]], [0]
    for i in range(len(path) - 1):
        n = max(1, int(np.ceil(np.linalg.norm(path[i + 1] - path[i]) / resolution)))
        s = np.arange(1, n + 1)[:, None] / n
        samples.append(path[i] + s * (path[i + 1] - path[i]))
        segment.extend([i] * n)
    return np.vstack(samples), np.asarray(segment)


def path_length(path: np.ndarray) -> float:
    """Joint-space L2 length of a piecewise-linear path, rad."""
    return float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum()) if len(path) > 1 else 0.0


def drop_duplicates(path: np.ndarray, tolerance: float = 1e-12) -> np.ndarray:
    """Drops waypoints within ``tolerance`` rad of their predecessor."""
    keep = np.concatenate([[True], np.linalg.norm(np.diff(path, axis=0), axis=1) > tolerance])
    return path[keep]
