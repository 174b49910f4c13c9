"""Damped Newton steps on a frame's pose, compiled (numba): the core of
``planning.search.cartesian.PoseNewton``.

The frame's pose comes from the kinematic chain of its body as ``sphere_fk.BatchedKinematics``
packs it (each step X_PC(q) = A + a B + b C, with a = sin q, b = cos q for a revolute joint,
a = q, b = 0 for a prismatic one; ``sphere_kernel._pose_chain``) and its fixed pose X_BE on the
body. The Jacobian is exact, by the same terms: dX_PC/dq = cos q B - sin q C (revolute) or B
(prismatic), so dX_WE/dq = X_WP dX_PC/dq X_CE, whose rotation part gives the angular velocity
column (dR_WE R_WE^T, a skew matrix) and whose translation part the linear one; the columns
are Drake's ``CalcJacobianSpatialVelocity`` of E's origin in W (angular first).

One Newton step per Python call cost ~0.25 ms through Drake's bindings (measured on the
pick-and-place sequence, 88 solves per sequence); here a whole solve is one compiled call.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from numba import njit

from planning.collision import sphere_kernel, trig
from planning.collision.sphere_kernel import _pose_chain, refresh_cache

_MAX_ERROR = 0.05  # m: a larger position error is cut to this in one Newton step
_MAX_TURN = 0.3  # rad: likewise for the rotation error
_DAMPING = 1e-3
_POSITION_TOLERANCE = 1e-4  # m
_ANGLE_TOLERANCE = 1e-3  # rad
_REST_TOLERANCE = 1e-4  # rad: the null-space move that ends a solve with a rest


@njit(cache=True)
def rotation_error(R_T, R, out):
    """Writes the rotation vector of R_T R^T (in W: the rotation that takes R to R_T) into
    ``out`` (3,) and returns its angle, rad, in [0, pi]. Near a half turn the skew part
    vanishes; the axis then comes from the symmetric part."""
    M = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            M[i, j] = R_T[i, 0] * R[j, 0] + R_T[i, 1] * R[j, 1] + R_T[i, 2] * R[j, 2]
    c = min(1.0, max(-1.0, 0.5 * (M[0, 0] + M[1, 1] + M[2, 2] - 1.0)))
    angle = np.arccos(c)
    vx = M[2, 1] - M[1, 2]
    vy = M[0, 2] - M[2, 0]
    vz = M[1, 0] - M[0, 1]
    if angle > 3.0:
        # (M + M^T) / 2 - cos(angle) I = (1 - cos(angle)) a a^T: the axis a from its largest
        # column, its sign from the skew part (2 sin(angle) a).
        i = 0
        for k in range(1, 3):
            if M[k, k] > M[i, i]:
                i = k
        norm = 0.0
        for k in range(3):
            out[k] = 0.5 * (M[k, i] + M[i, k]) - (c if k == i else 0.0)
            norm += out[k] * out[k]
        norm = np.sqrt(norm)
        sign = 1.0 if out[0] * vx + out[1] * vy + out[2] * vz >= 0.0 else -1.0
        for k in range(3):
            out[k] *= sign * angle / norm
        return angle
    scale = 0.5 if angle < 1e-8 else 0.5 * angle / np.sin(angle)
    out[0] = scale * vx
    out[1] = scale * vy
    out[2] = scale * vz
    return angle


@njit(cache=True)
def frame_pose(full, parent, kind, q_index, terms, body, X_BE, T, X):
    """X_WE (3, 4) of the frame into X, the chain's X_WC (J, 3, 4) into T, for the plant
    positions ``full``; ``body`` is the step of E's body (-1: the world)."""
    _pose_chain(full, parent, kind, q_index, terms, T)
    for i in range(3):
        for j in range(4):
            if body < 0:
                X[i, j] = X_BE[i, j]
                continue
            x = T[body, i, 0] * X_BE[0, j] + T[body, i, 1] * X_BE[1, j] + T[body, i, 2] * X_BE[2, j]
            X[i, j] = x + T[body, i, 3] if j == 3 else x


@njit(cache=True)
def frame_jacobian(full, parent, kind, q_index, terms, T, X, arm, J):
    """The spatial-velocity Jacobian of E's origin in W with respect to the arm's positions
    ``arm`` (plant indices), (6, len(arm)) into J (angular rows first), from ``frame_pose``'s
    T and X at ``full``."""
    J[:] = 0.0
    D = np.empty((3, 4))
    X_CE = np.empty((3, 4))
    dX = np.empty((3, 4))
    rotated = np.empty((3, 4))
    for s in range(len(parent)):
        if kind[s] == 0:
            continue
        column = -1
        for k in range(len(arm)):
            if arm[k] == q_index[s]:
                column = k
        if column < 0:
            continue
        # dX_PC/dq: cos q B - sin q C (revolute), B (prismatic: C is zero).
        c, n = 1.0, 0.0
        if kind[s] == 1:
            c, n = np.cos(full[q_index[s]]), -np.sin(full[q_index[s]])
        for i in range(3):
            for j in range(4):
                D[i, j] = c * terms[s, 1, i, j] + n * terms[s, 2, i, j]
        # X_CE = X_WC^-1 X_WE: R_WC^T (X_WE - p_WC) column by column.
        for i in range(3):
            for j in range(4):
                x = 0.0
                for k in range(3):
                    x += T[s, k, i] * (X[k, j] - (T[s, k, 3] if j == 3 else 0.0))
                X_CE[i, j] = x
        # dX_WE = R_WP (D X_CE): the parent's translation does not vary with q.
        p = parent[s]
        for i in range(3):
            for j in range(4):
                x = D[i, 0] * X_CE[0, j] + D[i, 1] * X_CE[1, j] + D[i, 2] * X_CE[2, j]
                if j == 3:
                    x += D[i, 3]
                dX[i, j] = x
        if p >= 0:
            for i in range(3):
                for j in range(4):
                    rotated[i, j] = (
                        T[p, i, 0] * dX[0, j] + T[p, i, 1] * dX[1, j] + T[p, i, 2] * dX[2, j]
                    )
            dX[:] = rotated
        # Angular: the skew matrix W = dR_WE R_WE^T; linear: dp_WE.
        for i, j, k in ((2, 1, 0), (0, 2, 1), (1, 0, 2)):  # J[k] = (W[i, j] - W[j, i]) / 2
            w_ij = dX[i, 0] * X[j, 0] + dX[i, 1] * X[j, 1] + dX[i, 2] * X[j, 2]
            w_ji = dX[j, 0] * X[i, 0] + dX[j, 1] * X[i, 1] + dX[j, 2] * X[i, 2]
            J[k, column] += 0.5 * (w_ij - w_ji)
        for i in range(3):
            J[3 + i, column] += dX[i, 3]


@njit(cache=True)
def _solve_spd(A, B):
    """A^-1 B for a symmetric positive definite A (m, m), B (m, n), by Cholesky."""
    m = A.shape[0]
    L = np.zeros((m, m))
    for i in range(m):
        for j in range(i + 1):
            x = A[i, j]
            for k in range(j):
                x -= L[i, k] * L[j, k]
            L[i, j] = np.sqrt(x) if i == j else x / L[j, j]
    Y = B.copy()
    for c in range(B.shape[1]):
        for i in range(m):
            x = Y[i, c]
            for k in range(i):
                x -= L[i, k] * Y[k, c]
            Y[i, c] = x / L[i, i]
        for i in range(m - 1, -1, -1):
            x = Y[i, c]
            for k in range(i + 1, m):
                x -= L[k, i] * Y[k, c]
            Y[i, c] = x / L[i, i]
    return Y


@njit(cache=True)
def newton(q0, frame, R_T, p_T, use_rotation, use_position, iterations, rest, use_rest):
    """Damped Newton steps (dq = J^T (J J^T + lambda^2 I)^-1 e, the error cut to ``_MAX_ERROR``
    m and ``_MAX_TURN`` rad, the joints clipped to [lower, upper]) placing frame E at the
    orientation R_T (3, 3) and/or position p_T (3,) (``use_rotation``, ``use_position``),
    from q0 (7,). With ``use_rest``, each step also moves the joints towards ``rest`` in the
    Jacobian's null space, until that move is below ``_REST_TOLERANCE``.

    ``frame`` is E's data: (template, arm, parent, kind, q_index, terms, body, X_BE, lower,
    upper): the plant positions of the joints other than the arm's (nq,), the arm's indices
    among them (7,), the chain of E's body (``BatchedKinematics.arrays``), the step of that
    body (-1: the world), E's pose on it (3, 4) and the arm's limits (7,), rad.

    Returns:
        (found, q): the joints within the tolerances, or found False after ``iterations``.
    """
    template, arm, parent, kind, q_index, terms, body, X_BE, lower, upper = frame
    full = template.copy()
    T = np.empty((len(parent), 3, 4))
    X = np.empty((3, 4))
    J = np.empty((6, len(arm)))
    e_r = np.zeros(3)
    rows = np.empty(6, dtype=np.int64)
    m = 0
    if use_rotation:
        for k in range(3):
            rows[m] = k
            m += 1
    if use_position:
        for k in range(3, 6):
            rows[m] = k
            m += 1
    n = len(arm)
    Jr = np.empty((m, n))
    A = np.empty((m, m))
    e = np.empty(m)
    y = np.empty(m)
    dq = np.empty(n)
    drift = np.empty(n)
    q = q0.copy()
    for _ in range(iterations):
        for k in range(len(arm)):
            full[arm[k]] = q[k]
        frame_pose(full, parent, kind, q_index, terms, body, X_BE, T, X)
        distance = 0.0
        if use_position:
            for i in range(3):
                distance += (p_T[i] - X[i, 3]) ** 2
            distance = np.sqrt(distance)
        angle = 0.0
        if use_rotation:
            angle = rotation_error(R_T, X[:, :3], e_r)
        there = distance < _POSITION_TOLERANCE and angle < _ANGLE_TOLERANCE
        if there and not use_rest:
            return True, q
        cut = min(1.0, _MAX_ERROR / max(distance, 1e-300), _MAX_TURN / max(angle, 1e-300))
        frame_jacobian(full, parent, kind, q_index, terms, T, X, arm, J)
        for r in range(m):
            k = rows[r]
            for c in range(n):
                Jr[r, c] = J[k, c]
            e[r] = cut * (e_r[k] if k < 3 else p_T[k - 3] - X[k - 3, 3])
        for r in range(m):
            for c in range(m):
                A[r, c] = 0.0
                for k in range(n):
                    A[r, c] += Jr[r, k] * Jr[c, k]
            A[r, r] += _DAMPING**2
        G = _solve_spd(A, Jr)  # (J J^T + lambda^2 I)^-1 J, (m, 7): its transpose is the inverse
        for k in range(n):
            dq[k] = 0.0
            for r in range(m):
                dq[k] += G[r, k] * e[r]
        if use_rest:
            for k in range(n):
                drift[k] = rest[k] - q[k]
            for r in range(m):  # minus its part in the row space: what is left moves E not
                along = 0.0
                for k in range(n):
                    along += Jr[r, k] * drift[k]
                y[r] = along
            size = 0.0
            for k in range(n):
                for r in range(m):
                    drift[k] -= G[r, k] * y[r]
                size += drift[k] * drift[k]
            if there and np.sqrt(size) < _REST_TOLERANCE:
                return True, q
            for k in range(n):
                dq[k] += drift[k]
        for k in range(len(q)):
            q[k] = min(max(q[k] + dq[k], lower[k]), upper[k])
    return False, q


@njit(cache=True)
def line(q_start, frame, R_targets, p_targets, jump_threshold, iterations):
    """``newton`` (``frame`` as there) from each pose of a line (R_targets (K, 3, 3), p_targets
    (K, 3)) to the next, from q_start, each solve starting from the last joint change repeated
    (along a straight line the next joints are that close to second order) and accepted when
    no joint moves more than ``jump_threshold`` rad.

    Returns:
        (path (M, 7): q_start and the joints of the poses reached in order, status: 0 every
        pose reached, 1 a solve failed, 2 a joint jumped).
    """
    lower, upper = frame[8], frame[9]
    dims = len(q_start)
    path = np.empty((len(p_targets) + 1, dims))
    path[0] = q_start
    guess = np.empty(dims)
    for k in range(len(p_targets)):
        for j in range(dims):
            guess[j] = path[k, j]
            if k > 0:
                guess[j] = min(max(2.0 * path[k, j] - path[k - 1, j], lower[j]), upper[j])
        found, q = newton(
            guess, frame, R_targets[k], p_targets[k], True, True, iterations, guess, False
        )
        if not found:
            return path[: k + 1].copy(), 1
        jump = 0.0
        for j in range(dims):
            jump = max(jump, abs(q[j] - path[k, j]))
        if jump > jump_threshold:
            return path[: k + 1].copy(), 2
        path[k + 1] = q
    return path, 0


def warm_up() -> None:
    """Compiles (first run on a machine) or loads ``newton`` and ``line`` now rather than in a
    request: a two-step chain (one revolute joint, one weld), position and orientation, with
    a rest."""
    terms = np.zeros((2, 3, 3, 4))
    terms[:, 0, :, :3] = np.eye(3)
    q = np.zeros(1)
    chain = (np.array([-1, 0]), np.array([1, 0]), np.zeros(2, dtype=np.int64), terms)
    frame = (q, np.zeros(1, dtype=np.int64), *chain, 1, np.eye(4)[:3], q - 1.0, q + 1.0)
    newton(q, frame, np.eye(3), np.zeros(3), True, True, 1, q, True)
    line(q, frame, np.eye(3)[None], np.zeros((1, 3)), 0.2, 1)


# Numba keys a cached function on its own file alone; these compile the kernel's code in.
refresh_cache(
    sys.modules[__name__],
    [Path(__file__), Path(sphere_kernel.__file__), Path(trig.__file__)],
    Path(newton._cache._cache_path),
)
