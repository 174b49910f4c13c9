"""Forward kinematics of many configurations at once, read from a Drake plant.

The kinematic tree (each joint's parent and child body, its fixed poses X_PF of the joint's
frame F on the parent P and X_CM of its frame M on the child C, and its axis) is read from the
plant once; then ``poses(q)`` evaluates X_WB of the wanted bodies for N configurations in
compiled loops (``planning.collision.sphere_kernel``, which also reads the tree as flat ``arrays``):
X_WC = X_WP X_PF X_FM(q) X_MC, where X_FM is a rotation about the axis by q (revolute),
a translation along it (prismatic) or fixed (weld). Other joint types are not supported.
X_PC(q) is affine in (1, sin q, cos q) for a revolute joint (Rodrigues: R = I + K^2 + sin(q) K
- cos(q) K^2, K the axis' cross-product matrix) and in (1, q) for a prismatic one, so each
body costs a weighted sum of constant 4x4 matrices and one 4x4 product.

``fold_fixed_steps`` folds the steps that cannot move in a plan (welds, and the fingers at the
scene's positions) into the arm joints' steps, ``fold_points`` moves the points they carry
along: the sphere model's kernels (``planning.collision.spheres``) run the Panda's 13 steps as 8
(one constant), which made the compiled search ~10 % faster on all of MBM (parallel runs).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.multibody.tree import JointIndex

from planning.collision.sphere_kernel import transforms


@dataclass
class _Step:
    child: int  # slot of the child body
    parent: int  # slot of the parent body (-1: world)
    kind: str  # "revolute", "prismatic" or "weld"
    terms: list[np.ndarray]  # constant 4x4 terms of X_PC(q) (see the module docstring)
    q_index: int  # position index of the joint (-1 for a weld)


class BatchedKinematics:
    """X_WB of chosen bodies for N configurations of a plant (revolute, prismatic, weld joints).

    Args:
        plant: a finalized MultibodyPlant.
        bodies: the body indices whose poses ``poses`` returns, in that order.

    Raises:
        NotImplementedError: a joint on the way to a wanted body has another type.
    """

    def __init__(self, plant, bodies):
        joint_to = {}
        for j in range(plant.num_joints()):
            joint = plant.get_joint(JointIndex(j))
            joint_to[int(joint.child_body().index())] = joint
        slots: dict[int, int] = {int(plant.world_body().index()): -1}
        self._steps: list[_Step] = []

        def visit(body: int) -> int:
            if body in slots:
                return slots[body]
            joint = joint_to.get(body)
            if joint is None:
                raise NotImplementedError(f"body {body} is floating (no joint)")
            parent = visit(int(joint.parent_body().index()))
            self._steps.append(_make_step(joint, len(self._steps), parent))
            slots[body] = len(self._steps) - 1
            return slots[body]

        self._out = [visit(int(b)) for b in bodies]
        self._arrays = None  # the tree as flat arrays, made on first use
        self.num_positions = plant.num_positions()

    def poses(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Returns (R_WB, p_WB) of the wanted bodies: shapes (K, N, 3, 3) and (K, N, 3).

        Args:
            q: (N, nq) plant positions (rad for revolute, m for prismatic joints).
        """
        T = self.transforms(q)
        return T[:, :, :3, :3], T[:, :, :3, 3]

    def transforms(self, q: np.ndarray) -> np.ndarray:
        """Returns X_WB of the wanted bodies as homogeneous matrices, (K, N, 4, 4)."""
        q = np.ascontiguousarray(np.atleast_2d(q), dtype=float)
        X = transforms(q, *self.arrays())  # (N, J, 3, 4)
        T = np.zeros((len(self._out), len(q), 4, 4))
        T[:, :, :3, :] = X[:, self._out].transpose(1, 0, 2, 3)
        T[:, :, 3, 3] = 1.0
        return T

    @property
    def out(self) -> np.ndarray:
        """The step (row of ``arrays``' tables) of each wanted body, in order."""
        return np.asarray(self._out, dtype=np.int64)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The tree as ``planning.collision.sphere_kernel`` reads it: (parent, kind, q_index,
        terms)."""
        if self._arrays is None:
            kinds = {"weld": 0, "revolute": 1, "prismatic": 2}
            terms = np.zeros((len(self._steps), 3, 3, 4))
            for k, s in enumerate(self._steps):
                terms[k, : len(s.terms)] = np.array(s.terms)[:, :3, :]
            self._arrays = (
                np.array([s.parent for s in self._steps], dtype=np.int64),
                np.array([kinds[s.kind] for s in self._steps], dtype=np.int64),
                np.array([max(s.q_index, 0) for s in self._steps], dtype=np.int64),
                terms,
            )
        return self._arrays


def _make_step(joint, slot: int, parent: int) -> _Step:
    X_PF = joint.frame_on_parent().GetFixedPoseInBodyFrame().GetAsMatrix4()
    X_MC = joint.frame_on_child().GetFixedPoseInBodyFrame().inverse().GetAsMatrix4()
    kind = joint.type_name()
    if kind == "revolute":
        a = np.asarray(joint.revolute_axis(), dtype=float)
        K = np.zeros((4, 4))
        K[:3, :3] = [[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]]
        middle = [np.eye(4) + K @ K, K, -(K @ K)]
    elif kind == "prismatic":
        D = np.zeros((4, 4))
        D[:3, 3] = joint.translation_axis()
        middle = [np.eye(4), D]
    elif kind == "weld":
        middle = [joint.X_FM().GetAsMatrix4()]
    else:
        raise NotImplementedError(f"joint {joint.name()} of type {kind}")
    terms = [X_PF @ M @ X_MC for M in middle]
    q_index = joint.position_start() if kind != "weld" else -1
    return _Step(slot, parent, kind, terms, q_index)


def fold_fixed_steps(parent, kind, q_index, terms, template, arm):
    """The tree of ``BatchedKinematics.arrays`` with every step that cannot move in a plan
    folded into the nearest step that can: welds, and joints other than the arm's (the
    fingers), which stay at their ``template`` positions. Forward kinematics then costs one
    step per arm joint and one constant step per fixed body hanging from the world (the
    Panda's 13 steps become 8: its base, then the first joint's step with the base's pose
    taken in): the points of a folded step are moved into the frame of the step it was folded
    into (``fold_points``).

    Args:
        parent, kind, q_index, terms: the tree (``BatchedKinematics.arrays``).
        template: (nq,) plant positions of the joints other than the arm's.
        arm: (7,) the arm's position indices.

    Returns:
        ((parent, kind, q_index, terms) of the folded tree, offsets): ``offsets[s]`` is
        (the folded step carrying old step s, X (4, 4) of s's frame in that step's frame);
        a step that hangs from the world through fixed steps alone gets a constant step of
        its own, X_WS, with X the identity.
    """
    moving = {int(k) for k in arm}
    new_parent, new_kind, new_q, new_terms, offsets = [], [], [], [], []

    def add(p: int, k: int, qi: int, t: np.ndarray) -> int:
        new_parent.append(p)
        new_kind.append(k)
        new_q.append(qi)
        new_terms.append(t)
        return len(new_parent) - 1

    above = []  # per old step: (folded step or -1 for the world, X of it in that frame)
    for s in range(len(parent)):
        base, M = (-1, np.eye(4)) if parent[s] < 0 else above[int(parent[s])]
        if kind[s] != 0 and int(q_index[s]) in moving:
            # X_base,C = M (A + a B + b C): A takes M's translation, B and C its rotation.
            t = np.empty((3, 3, 4))
            t[0] = M[:3, :3] @ terms[s, 0]
            t[0, :, 3] += M[:3, 3]
            t[1] = M[:3, :3] @ terms[s, 1]
            t[2] = M[:3, :3] @ terms[s, 2]
            step = add(base, int(kind[s]), int(q_index[s]), t)
            above.append((step, np.eye(4)))
            offsets.append((step, np.eye(4)))
            continue
        a = b = 0.0
        if kind[s] == 1:
            a, b = np.sin(template[q_index[s]]), np.cos(template[q_index[s]])
        elif kind[s] == 2:
            a = template[q_index[s]]
        X = np.eye(4)
        X[:3] = terms[s, 0] + a * terms[s, 1] + b * terms[s, 2]
        X = M @ X
        above.append((base, X))
        if base >= 0:
            offsets.append((base, X))
        else:  # fixed in the world: a constant step (no product in the kinematics)
            t = np.zeros((3, 3, 4))
            t[0] = X[:3]
            offsets.append((add(-1, 0, 0, t), np.eye(4)))
    tree = (
        np.array(new_parent, dtype=np.int64),
        np.array(new_kind, dtype=np.int64),
        np.array(new_q, dtype=np.int64),
        np.array(new_terms).reshape(-1, 3, 3, 4),
    )
    return tree, offsets


def fold_points(offsets, steps, points):
    """(steps, points) of points fixed on old steps (``steps`` (K,), ``points`` (K, 3), m)
    moved to the folded tree of ``fold_fixed_steps``: (new steps (K,), new points (K, 3))."""
    step_of = np.array([step for step, _ in offsets], dtype=np.int64)
    X = np.array([X for _, X in offsets]).reshape(-1, 4, 4)
    steps = np.asarray(steps, dtype=np.int64)
    moved = np.einsum("kij,kj->ki", X[steps, :3, :3], points) + X[steps, :3, 3]
    return step_of[steps], np.ascontiguousarray(moved)
