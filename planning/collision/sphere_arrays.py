"""The arrays of the sphere model's compiled kernels (``sphere_kernel.KernelData``,
``hull_kernel.HullData``): the robot's spheres grouped for culling with their thresholds, its
exact collision shapes, the speed bounds of its points, and the world's objects as rows.

``SphereCollisionModel`` (``planning.collision.spheres``) reads the scene (bodies, held objects,
the checker's filters and paddings) and calls these when what they depend on changes. Every
threshold has a margin of ``MARGIN`` on the safe side (the exact shapes' ``hull_kernel.MARGIN``).
Each body's spheres are cut into groups of up to ``GROUP`` neighbours with a bounding sphere, and
each body gets a bounding sphere of its groups: configurations are culled per body, then per
group, before spheres are looked at.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planning.collision import sphere_kernel as _kernel
from planning.collision.hull_kernel import MARGIN as HULL_MARGIN
from planning.collision.hull_kernel import HullData
from planning.collision.sphere_cover import SphereSet
from planning.collision.sphere_fk import fold_points

MARGIN = 1e-5  # m, added on the safe side of every comparison (covers rounding)
GROUP = 4  # spheres per culling group


class Filters(NamedTuple):
    """What the checker checks, read from the scene (by body index)."""

    filtered: np.ndarray  # the checker's filtered collision matrix (0: checked)
    padding: np.ndarray  # its padding matrix, m
    world_body: int  # the world body's index
    checked: set  # the body pairs (a, b) it checks, a before b in the model's order


class RobotArrays(NamedTuple):
    """``robot_arrays``' answer.

    Attributes:
        arrays: ``KernelData``'s fields from ``sphere_step`` to ``pair_in`` but the
            ``objects``: on the kinematic steps before folding (``fold_points``).
        sphere_slot: (S,) each sphere's body slot (the model's bodies, for its transforms).
        sphere_body: (S,) each sphere's body, as its index among the bodies with spheres.
        radius: (S,) the spheres' outer radii, m.
        point_norm: (L,) how far from each body's origin any point the checks use lies, m.
    """

    arrays: dict
    sphere_slot: np.ndarray
    sphere_body: np.ndarray
    radius: np.ndarray
    point_norm: np.ndarray


def body_groups(spheres: SphereSet) -> tuple:
    """(groups of a body's spheres as index arrays into ``spheres``, a bounding sphere of each
    (``_bound``), one of all those groups, and how far from the body's origin any point the
    checks use lies (sphere, group or body centre; for ``speed_table``))."""
    local = _groups(np.arange(len(spheres.radius)), spheres.p_BS)
    bounds = [_bound(spheres.p_BS[m], spheres.radius[m]) for m in local]
    centres = np.array([c for c, _ in bounds]).reshape(-1, 3)
    whole = _bound(centres, np.array([r for _, r in bounds]))
    norm = max(
        np.linalg.norm(whole[0]),
        np.linalg.norm(centres, axis=1).max(initial=0.0),
        np.linalg.norm(spheres.p_BS, axis=1).max(initial=0.0),
    )
    return local, bounds, whole, norm


def robot_arrays(sets, groups_of, step, slot, filters: Filters) -> RobotArrays:
    """The robot's ``KernelData`` fields from its sphere sets (see ``RobotArrays``), on the
    kinematic steps before folding.

    Args:
        sets: {body: ``SphereSet``}, the bodies with spheres (held objects' on the attachment
            body), in the model's order.
        groups_of: ``(body, spheres) -> body_groups(spheres)``, maybe cached.
        step, slot: the kinematic step of each of the model's bodies, and each body's slot.
        filters: which pairs the checker checks, and their paddings.
    """
    filtered, padding, world_body, checked = filters
    present = list(sets)
    counts = [len(sets[b].radius) for b in present]
    sphere_slot = np.repeat([slot[b] for b in present], counts).astype(int)
    sphere_body = np.repeat(np.arange(len(present)), counts).astype(int)
    p_BS = np.vstack([sets[b].p_BS for b in present])
    radius = np.concatenate([sets[b].radius for b in present])
    inner = np.concatenate([sets[b].inner for b in present])
    # Groups of up to GROUP neighbouring spheres of one body, each with a bounding sphere,
    # and a bounding sphere of each body's groups: configurations are culled per body, then
    # per group, before spheres are looked at.
    groups, bounds, group_body, body_bounds, point_norm = [], [], [], [], []
    offset = 0
    for k, b in enumerate(present):
        local, local_bounds, body_bound, norm = groups_of(b, sets[b])
        groups += [(b, m + offset) for m in local]
        bounds += local_bounds
        group_body += [k] * len(local)
        body_bounds.append(body_bound)
        point_norm.append(norm)
        offset += len(sets[b].radius)
    group_centre = np.array([c for c, _ in bounds]).reshape(-1, 3)
    group_radius = np.array([r for _, r in bounds])
    group_body = np.array(group_body, dtype=np.int64)
    members = np.zeros((len(groups), GROUP), dtype=np.int64)
    for g, (_, m) in enumerate(groups):
        members[g, : len(m)] = m
    used = np.arange(GROUP)[None, :] < np.array([len(m) for _, m in groups])[:, None]
    # Environment: groups of bodies not filtered against the world (not the welded base).
    env = [g for g, (b, _) in enumerate(groups) if filtered[b, world_body] == 0]
    world_pad = np.array([padding[b, world_body] for b in present])
    pad = world_pad[group_body[env]][:, None]
    r_out = radius[members[env]] + np.maximum(pad, 0.0) + MARGIN
    r_in = inner[members[env]]
    body_radius = np.array([r for _, r in body_bounds])
    body_centre = np.array([c for c, _ in body_bounds]).reshape(-1, 3)
    arrays = dict(
        sphere_step=step[sphere_slot],
        p_BS=p_BS,
        body_step=step[[slot[b] for b in present]],
        p_BL=body_centre,
        body_reach=body_radius + np.maximum(world_pad, 0.0) + MARGIN,
        group_step=step[[slot[b] for b, _ in groups]],
        p_BG=group_centre,
        env_group=np.array(env, dtype=np.int64),
        env_body=group_body[env],
        env_reach2=(group_radius[env] + np.maximum(pad[:, 0], 0.0) + MARGIN) ** 2,
        env_member=members[env],
        env_out=np.where(used[env], _squared(r_out), -1.0),
        env_in=np.where(used[env] & (r_in > 0), _squared(r_in + pad - MARGIN), -1.0),
    )
    # Self-collision: group pairs of the body pairs the checker checks, sphere pairs padded
    # to GROUP**2 per group pair, in runs per body pair.
    checked_bodies = np.zeros((len(present), len(present)), dtype=bool)
    where = {b: k for k, b in enumerate(present)}
    for a, b in checked:
        checked_bodies[where[a], where[b]] = True
    # Group pairs (g, h) of checked body pairs, sorted by (body of g, body of h, g, h).
    g, h = np.nonzero(checked_bodies[group_body[:, None], group_body[None, :]])
    key = group_body[g] * len(present) + group_body[h]
    order = np.lexsort((h, g, key))
    g, h, key = g[order].astype(np.int64), h[order].astype(np.int64), key[order]
    first = np.flatnonzero(np.r_[True, key[1:] != key[:-1]]) if len(key) else key
    body_pairs = [(int(group_body[g[k]]), int(group_body[h[k]])) for k in first]
    run = np.r_[first, len(key)]
    # Every (sphere of g, sphere of h) of each checked group pair, GROUP**2 per row.
    shape = (len(g), GROUP * GROUP)
    pair_a = np.broadcast_to(members[g][:, :, None], (len(g), GROUP, GROUP)).reshape(shape)
    pair_b = np.broadcast_to(members[h][:, None, :], (len(h), GROUP, GROUP)).reshape(shape)
    valid = (used[g][:, :, None] & used[h][:, None, :]).reshape(shape)
    owner_of = np.array([b for b, _ in groups], dtype=np.int64)  # body index of each group
    pad = padding[owner_of[g], owner_of[h]].reshape(-1, 1)
    reach = group_radius[g] + group_radius[h] + np.maximum(pad[:, 0], 0.0) + MARGIN
    r_out = radius[pair_a] + radius[pair_b] + np.maximum(pad, 0.0) + MARGIN
    pair_out = np.where(valid, _squared(r_out), -1.0)
    ok = valid & (inner[pair_a] > 0) & (inner[pair_b] > 0)
    pair_in = np.where(ok, _squared(inner[pair_a] + inner[pair_b] + pad - MARGIN), -1.0)
    body_pad = np.array([max(padding[present[i], present[j]], 0.0) for i, j in body_pairs])
    body_pairs = np.array(body_pairs, dtype=np.int64).reshape(-1, 2)
    arrays.update(
        body_pair=body_pairs,
        body_pair_reach2=(
            body_radius[body_pairs[:, 0]] + body_radius[body_pairs[:, 1]] + body_pad + MARGIN
        )
        ** 2,
        body_pair_start=np.asarray(run, dtype=np.int64),
        pair_group=np.column_stack((g, h)).astype(np.int64).reshape(-1, 2),
        pair_reach2=reach**2,
        # The first group of each pair against the other body's bounding sphere (which holds
        # every group of that body): out of this reach, none of its pairs with that body is
        # within theirs.
        pair_side_reach2=(
            group_radius[g] + body_radius[group_body[h]] + np.maximum(pad[:, 0], 0.0) + MARGIN
        )
        ** 2,
        pair_a=pair_a,
        pair_b=pair_b,
        pair_out=pair_out,
        pair_in=pair_in,
    )
    arrays = {k: np.ascontiguousarray(v) for k, v in arrays.items()}
    return RobotArrays(arrays, sphere_slot, sphere_body, radius, np.array(point_norm))


def hull_arrays(shapes, step, slot, filters: Filters) -> dict:
    """``HullData``'s fields but ``speed``, on the kinematic steps before folding: each robot
    shape's step, vertices, swept radius and bounding sphere, its clearance to prove to the
    world (-1: filtered), its body (the position in ``shapes``), and the shape pairs of the body
    pairs the checker checks (``filters``).

    Args:
        shapes: {body: [(vertices (V, 3), swept radius)]}, the bodies in the model's order;
        step, slot: as ``robot_arrays``'.
    """
    filtered, padding, world_body, checked = filters
    present = list(shapes)
    geom_step, verts, radius, centre, bound, world, owner = [], [], [], [], [], [], []
    geom_body = []
    for k, b in enumerate(present):
        for v, r in shapes[b]:
            c = v.mean(axis=0)
            geom_step.append(step[slot[b]])
            verts.append(v)
            radius.append(r)
            centre.append(c)
            bound.append(float(np.linalg.norm(v - c, axis=1).max()) + r)
            pad = max(padding[b, world_body], 0.0) + HULL_MARGIN
            world.append(pad if filtered[b, world_body] == 0 else -1.0)
            owner.append(b)
            geom_body.append(k)
    owner = np.array(owner, dtype=np.int64)
    pairs, gaps = [], []
    for a, b in sorted(checked):
        gap = max(padding[a, b], 0.0) + HULL_MARGIN
        for g in np.flatnonzero(owner == a):
            for e in np.flatnonzero(owner == b):
                pairs.append((g, e))
                gaps.append(gap)
    return dict(
        geom_step=np.array(geom_step, dtype=np.int64),
        vert_start=np.r_[0, np.cumsum([len(v) for v in verts])].astype(np.int64),
        vert=np.vstack(verts) if verts else np.zeros((0, 3)),
        geom_radius=np.array(radius, dtype=float),
        geom_centre=np.array(centre, dtype=float).reshape(-1, 3),
        geom_bound=np.array(bound, dtype=float),
        geom_world=np.array(world, dtype=float),
        pair=np.array(pairs, dtype=np.int64).reshape(-1, 2),
        pair_gap=np.array(gaps, dtype=float),
        geom_body=np.array(geom_body, dtype=np.int64),
    )


def shape_reach(shapes) -> np.ndarray:
    """How far from each body's origin any point of its shapes lies, m, (B,): the farthest
    vertex plus the swept radius (``hull_arrays``' ``shapes``; 0 for a body without any)."""
    return np.array(
        [
            max((float(np.linalg.norm(v, axis=1).max()) + r for v, r in shapes[b]), default=0.0)
            for b in shapes
        ]
    )


def folded_hulls(raw: dict, offsets, speed: np.ndarray) -> HullData:
    """``HullData`` of ``hull_arrays``' fields ``raw``, moved onto the folded tree's steps
    (``sphere_fk.fold_fixed_steps``' ``offsets``), with the shapes' speed bounds ``speed``
    (B, D)."""
    counts = np.diff(raw["vert_start"])
    _, vert = fold_points(offsets, np.repeat(raw["geom_step"], counts), raw["vert"])
    geom_step, centre = fold_points(offsets, raw["geom_step"], raw["geom_centre"])
    fields = dict(raw, geom_step=geom_step, vert=vert, geom_centre=centre, speed=speed)
    return HullData(**{k: np.ascontiguousarray(v) for k, v in fields.items()})


def speed_table(parent, kind, q_index, terms, template, arm, body_step, point_norm):
    """A bound on the speed of the points of each body per rad of each arm joint, (L, D), m/rad,
    valid in every configuration (``KernelData.speed``).

    Step s of the tree maps a point p of its child frame to X_PC(q) [p; 1] with
    X_PC = A + a B + b C (``sphere_fk``); for a revolute joint its derivative in q is
    (cos q B - sin q C) [p; 1], no longer than |[B; C] [p; 1]| <= sigma |p| + |t|, where sigma
    is the largest singular value of the stacked rotation parts of B and C (6 x 3) and t their
    stacked translations. The parent frame moves rigidly with the rest of the tree, so that is
    also the point's speed in the world. |p| in step s's frame is at most the point's distance
    from its body's origin (``point_norm``) plus the largest translation of every step between
    them. A prismatic arm joint gets no bound (inf)."""
    arm_of = {int(k): j for j, k in enumerate(arm)}
    A, B, C = terms[:, 0], terms[:, 1], terms[:, 2]  # (J, 3, 4) each
    sigma = np.linalg.norm(np.concatenate([B[:, :, :3], C[:, :, :3]], axis=1), 2, axis=(1, 2))
    shift = np.linalg.norm(np.concatenate([B[:, :, 3], C[:, :, 3]], axis=1), axis=1)
    # The largest translation of each step: a joint of the arm anywhere, another at the
    # template's position (a weld has a = b = 0).
    held = np.where(kind == 0, 0.0, template[q_index])
    a = np.where(kind == 1, np.sin(held), held)
    c = np.where(kind == 1, np.cos(held), 0.0)
    fixed = np.linalg.norm(A[:, :, 3] + a[:, None] * B[:, :, 3] + c[:, None] * C[:, :, 3], axis=1)
    moving = np.array([kind[s] != 0 and int(q_index[s]) in arm_of for s in range(len(kind))])
    largest = np.where(moving, np.linalg.norm(A[:, :, 3], axis=1) + shift, fixed)
    largest[moving & (kind == 2)] = np.inf  # a prismatic arm joint: no bound
    speed = np.zeros((len(body_step), len(arm)))
    for b, step in enumerate(body_step):
        reach = float(point_norm[b])
        s = int(step)
        while s >= 0:
            if moving[s]:
                speed[b, arm_of[int(q_index[s])]] = (
                    sigma[s] * reach + shift[s] if kind[s] == 1 else np.inf
                )
            reach += largest[s]
            s = int(parent[s])
    return np.ascontiguousarray(speed)


def _squared(reach: np.ndarray) -> np.ndarray:
    """reach**2 where reach > 0, else -1 (never above a squared distance)."""
    return np.where(reach > 0, reach * reach, -1.0)


def _bound(centres: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, float]:
    """A sphere containing spheres (centres (P, 3), radii (P,)): its centre and radius, m."""
    centre = centres.mean(axis=0)
    return centre, float((np.linalg.norm(centres - centre, axis=1) + radii).max())


def _groups(members: np.ndarray, p: np.ndarray, size: int = GROUP) -> list[np.ndarray]:
    """Splits sphere indices into groups of at most ``size`` neighbours: sorted along the
    direction in which their centres p[members] spread most, then cut in runs."""
    if len(members) <= size:
        return [members]
    x = p[members] - p[members].mean(axis=0)
    direction = np.linalg.svd(x, full_matrices=False)[2][0]
    ordered = members[np.argsort(x @ direction)]
    return [ordered[k : k + size] for k in range(0, len(ordered), size)]


def primitives(objects) -> np.ndarray:
    """World boxes, cylinders and spheres as the kernel's object rows (``KernelData``): object
    O as its kind, W = R_WO^T and offset = R_WO^T p_WO (so p_OQ = W p_WQ - offset), its sizes
    (box: half sizes; cylinder: radius, half length; sphere: radius) and the corners of an
    axis-aligned box around it, m."""
    objects = list(objects)
    kinds = {"box": 0, "cylinder": 1, "sphere": 2}
    W = np.array([o.X_PO.rotation().matrix().T for o in objects]).reshape(-1, 3, 3)
    p = np.array([o.X_PO.translation() for o in objects]).reshape(-1, 3)
    size = np.zeros((len(objects), 3))
    half = np.zeros((len(objects), 3))  # half extents along the object's own axes
    for k, o in enumerate(objects):
        if o.shape == "box":
            size[k] = half[k] = np.asarray(o.size) / 2
        elif o.shape == "cylinder":
            size[k, :2] = o.size[0], o.size[1] / 2
            half[k] = o.size[0], o.size[0], o.size[1] / 2
        else:
            size[k, 0] = o.size[0]
            half[k] = o.size[0]
    extent = np.einsum("kji,kj->ki", np.abs(W), half)  # |R_WO| half
    rows = np.zeros((len(objects), _kernel.OBJ_COLUMNS))
    rows[:, _kernel.OBJ_KIND] = [kinds[o.shape] for o in objects]
    rows[:, _kernel.OBJ_W : _kernel.OBJ_W + 9] = W.reshape(-1, 9)
    rows[:, _kernel.OBJ_OFFSET : _kernel.OBJ_OFFSET + 3] = np.einsum("kij,kj->ki", W, p)
    rows[:, _kernel.OBJ_SIZE : _kernel.OBJ_SIZE + 3] = size
    rows[:, _kernel.OBJ_LOWER : _kernel.OBJ_LOWER + 3] = p - extent
    rows[:, _kernel.OBJ_UPPER : _kernel.OBJ_UPPER + 3] = p + extent
    return rows
