"""A segment that touches an obstacle between its samples only, for the path audit's and the
planner's tests (``drake_sim.tools.path_audit``, ``validation.swept``).

A thin vertical blade stands in the circle that the hand's farthest point from joint 1's axis
sweeps when joint 1 turns, ``DEPTH`` into it: turning joint 1 through a few mrad around the
configuration ``Q_CONTACT``, the hand touches it, elsewhere it does not. ``grazing_segment``
puts the blade into a scene, measures that interval of contact with Drake's signed distance, and
returns a 0.1 rad segment whose samples every 0.01 rad (t = i/n, the planner's samples without
``swept``) and whose cells' centres (t = (i - 1/2)/n) all lie outside the contact, which sits
between two of them.
"""

from __future__ import annotations

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.multibody.tree import BodyIndex

from drake_sim.tools.path_audit import AuditTarget, planning_scene_target
from planning.collision.sphere_robot import robot_hulls

Q_CONTACT = np.array([0.3, 0.2, 0.0, -1.8, 0.3, 2.0, 1.1])
DEPTH = 2e-5  # m, how far the blade reaches into the swept circle
JOINT_NAMES = [f"panda_joint{i}" for i in range(1, 8)]
SCAN = np.arange(-0.01, 0.01, 1e-4)  # rad of joint 1 around Q_CONTACT, where contact is sought


def farthest_point(scene, q) -> np.ndarray:
    """The point of the robot's collision shapes farthest from the world's z axis (joint 1's),
    at q: p_W (3,)."""
    plant = scene.plant
    context = scene.plant_context(q)
    inspector = scene.checker.MakeStandaloneModelContext().GetQueryObject().inspector()
    bodies = [
        int(b)
        for b in plant.GetBodyIndices(scene.model.instance)
        if plant.GetCollisionGeometriesForBody(plant.get_body(b))
    ]
    best, point = -1.0, None
    for body, shapes in robot_hulls(plant, inspector, bodies).items():
        X = plant.EvalBodyPoseInWorld(context, plant.get_body(BodyIndex(body)))
        for v, r in shapes:
            p = v @ X.rotation().matrix().T + X.translation()
            radius = np.hypot(p[:, 0], p[:, 1]) + r
            k = int(np.argmax(radius))
            if radius[k] > best:
                best = radius[k]
                point = p[k] * (radius[k] / np.hypot(p[k, 0], p[k, 1]))  # out by r, horizontally
                point[2] = p[k, 2]
    return point


def signed_distance(target: AuditTarget, q) -> float:
    """The least signed distance between the robot and anything at the arm configuration q."""
    return target.closest(target.positions(dict(zip(JOINT_NAMES, q, strict=True))), 0.01)[0]


def grazing_segment(scene) -> tuple[np.ndarray, np.ndarray, AuditTarget]:
    """Adds the blade ("blade") to ``scene`` and returns (q_a, q_b, the audit's target on that
    scene): the segment of joint 1 whose planner samples and cell centres are free while it
    touches the blade between them (asserted here)."""
    p = farthest_point(scene, Q_CONTACT)
    phi = np.arctan2(p[1], p[0])
    radial = np.hypot(p[0], p[1])
    size = np.array([0.05, 0.001, 0.05])  # radial, tangential, vertical
    centre_r = radial - DEPTH + size[0] / 2
    X = RigidTransform(
        RotationMatrix(RollPitchYaw(0.0, 0.0, phi)),
        [centre_r * np.cos(phi), centre_r * np.sin(phi), p[2]],
    )
    scene.add_box("blade", size, X)
    target = planning_scene_target(scene)
    turned = Q_CONTACT + SCAN[:, None] * np.eye(7)[0]
    touching = SCAN[[signed_distance(target, q) < 0.0 for q in turned]]
    lo, hi = touching.min(), touching.max()
    assert hi - lo < 0.004, "the contact must fit between a sample and a cell centre"
    x = (lo + hi) / 2 - 0.0025  # the gap (x, x + 0.005) holds the contact
    q_a = Q_CONTACT + (x - 0.05) * np.eye(7)[0]
    q_b = q_a + 0.1 * np.eye(7)[0]
    t = np.r_[np.arange(11) / 10, (np.arange(10) + 0.5) / 10]
    for q in q_a + t[:, None] * (q_b - q_a):
        assert signed_distance(target, q) > 0.0
    return q_a, q_b, target
