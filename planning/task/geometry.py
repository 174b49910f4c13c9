"""Geometry the pick-and-place task needs: box overlap and top-down grasp frames."""

from __future__ import annotations

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix


def boxes_overlap(size_a, X_WA: RigidTransform, size_b, X_WB: RigidTransform, margin=0.0) -> bool:
    """True when two boxes (full extents, m; centre poses) are closer than ``margin`` (m) or
    intersect: the separating-axis test on the 15 candidate axes, with each box grown by
    ``margin / 2`` on every side."""
    R_a, R_b = X_WA.rotation().matrix(), X_WB.rotation().matrix()
    half_a = 0.5 * np.asarray(size_a, dtype=float) + 0.5 * margin
    half_b = 0.5 * np.asarray(size_b, dtype=float) + 0.5 * margin
    d = X_WB.translation() - X_WA.translation()
    axes = [R_a[:, i] for i in range(3)] + [R_b[:, i] for i in range(3)]
    for i in range(3):
        for j in range(3):
            axis = np.cross(R_a[:, i], R_b[:, j])
            if np.linalg.norm(axis) > 1e-9:
                axes.append(axis / np.linalg.norm(axis))
    for axis in axes:
        reach_a = np.sum(half_a * np.abs(R_a.T @ axis))
        reach_b = np.sum(half_b * np.abs(R_b.T @ axis))
        if abs(d @ axis) > reach_a + reach_b:
            return False
    return True


def top_down_grasps(X_WO: RigidTransform, size, max_width: float) -> list[RigidTransform]:
    """Orientations R_WG of a hand pointing down (its z axis along -z_W) whose fingers close
    (along the hand's y axis) across one of the object's horizontal sides no wider than
    ``max_width``; returned as poses at the object's centre, four yaws per side that fits."""
    R_WO = X_WO.rotation()
    grasps = []
    for k in range(4):
        # Closing along the object's y axis for even k, its x axis for odd k.
        width = size[1] if k % 2 == 0 else size[0]
        if width > max_width:
            continue
        R_OG = RotationMatrix.MakeZRotation(k * np.pi / 2) @ RotationMatrix.MakeXRotation(np.pi)
        grasps.append(RigidTransform(R_WO @ R_OG, X_WO.translation()))
    return grasps


def rotation_distance(R_a: RotationMatrix, R_b: RotationMatrix) -> float:
    """The angle of R_a⁻¹ R_b, rad."""
    return float(R_a.InvertAndCompose(R_b).ToAngleAxis().angle())
