"""Benchmark of the lidar's two possible implementations: ``python benchmarks/lidar_benchmark.py``.

On an arena-like scene built here (a 6 m x 5 m room walled by boxes, ``--boxes`` rotated boxes,
``--cylinders`` cylinders and a concave star-shaped mesh prism of about 4 000 triangles, all
0.3 m tall and welded to the world) and a lidar 0.17 m above the floor at a few poses inside it:

* geometric ray casting (``drake_sim.systems.sensors.ray_casting``, what ``Lidar`` uses): cost
  per 360-beam scan of ``Lidar.exact_ranges`` (median of ``--scans`` scans, ms), the first scan
  (which builds the cache), and of ``Lidar.scan_now`` (with the noise and the ``LaserScan``);
* the same for the ``sick_tim571`` preset (811 beams, 25 m) from the last pose;
* depth renders: four ``RenderEngineVtk`` depth cameras of 90 degrees, ``--pixels`` columns and
  3 rows each, the beam read from the column nearest to it (written here only to measure it);

each with its error against an exact 2D reference computed here (segments and circles in the
scan plane): the largest and the 99th percentile of |range - exact| over all beams with a finite
exact range, and the beams one reports finite and the other not. Prints the machine too;
``--json FILE`` also writes the figures for ``python -m benchmarks.report``.
Not a test: times depend on the machine.
"""

import argparse
import json
import math
import os
import platform
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
from pydrake.geometry import (
    Box,
    ClippingRange,
    Cylinder,
    DepthRange,
    DepthRenderCamera,
    MakeRenderEngineVtk,
    Mesh,
    RenderCameraCore,
    RenderEngineVtkParams,
)
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, CoulombFriction
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.sensors import CameraInfo

from drake_sim.base.cli import output_file
from drake_sim.base.files import write_atomic
from drake_sim.systems.sensors.lidar import (
    Lidar,
    LidarConfig,
    lidar_preset_file,
    load_lidar_config,
)

ROOM = (6.0, 5.0)  # m
HEIGHT = 0.3  # m, of every wall and obstacle
SCAN_Z = 0.17  # m, the scan plane above the floor
STAR = {"centre": (1.6, -1.2), "points": 1024, "r_in": 0.18, "r_out": 0.35}  # the mesh


def star_outline(points: int, r_in: float, r_out: float) -> np.ndarray:
    """A star-shaped concave outline (points, 2), m: radius alternating between r_in and r_out."""
    a = 2 * np.pi * np.arange(points) / points
    r = np.where(np.arange(points) % 16 < 8, r_out, r_in)
    return np.column_stack([r * np.cos(a), r * np.sin(a)])


def write_prism_obj(path: Path, outline: np.ndarray, height: float) -> int:
    """Writes a prism over ``outline`` (star-shaped about the origin) from z = 0 to ``height``
    as an OBJ of triangles; returns the number of triangles."""
    n = len(outline)
    lines = [f"v {x:.9f} {y:.9f} {z:.9f}" for z in (0.0, height) for x, y in outline]
    lines += ["v 0 0 0", f"v 0 0 {height}"]
    faces = []
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, n + j), (i, n + j, n + i), (2 * n, j, i), (2 * n + 1, n + i, n + j)]
    points = np.array(
        [(x, y, z) for z in (0.0, height) for x, y in outline] + [(0, 0, 0), (0, 0, height)]
    )
    for k, (a, b, c) in enumerate(faces):
        normal = np.cross(points[b] - points[a], points[c] - points[a])
        normal /= np.linalg.norm(normal)
        lines.append(f"vn {normal[0]:.9f} {normal[1]:.9f} {normal[2]:.9f}")
        lines.append(f"f {a + 1}//{k + 1} {b + 1}//{k + 1} {c + 1}//{k + 1}")
    path.write_text("\n".join(lines) + "\n")
    return len(faces)


def scene_layout(rng: np.random.Generator, boxes: int, cylinders: int):
    """Returns the walls and boxes [(cx, cy, sx, sy, yaw)] and cylinders [(cx, cy, r)], m, rad."""
    sx, sy, t = ROOM[0] / 2, ROOM[1] / 2, 0.05
    rects = [
        (0.0, sy + t / 2, ROOM[0] + 2 * t, t, 0.0),
        (0.0, -sy - t / 2, ROOM[0] + 2 * t, t, 0.0),
        (sx + t / 2, 0.0, t, ROOM[1], 0.0),
        (-sx - t / 2, 0.0, t, ROOM[1], 0.0),
    ]
    for _ in range(boxes):
        x, y = rng.uniform(-sx + 0.3, sx - 0.3), rng.uniform(-sy + 0.3, sy - 0.3)
        rects.append((x, y, *rng.uniform(0.1, 0.4, 2), rng.uniform(0, np.pi)))
    circles = [
        (rng.uniform(-sx + 0.3, sx - 0.3), rng.uniform(-sy + 0.3, sy - 0.3), rng.uniform(0.05, 0.2))
        for _ in range(cylinders)
    ]
    return rects, circles


def build(rects, circles, mesh_file: Path):
    """The plant, scene graph (with a VTK renderer) and diagram of the scene with a lidar body."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    scene_graph.AddRenderer("vtk", MakeRenderEngineVtk(RenderEngineVtkParams()))
    world, friction = plant.world_body(), CoulombFriction()
    shapes = [
        (RigidTransform(RotationMatrix.MakeZRotation(yaw), [x, y, HEIGHT / 2]), Box(a, b, HEIGHT))
        for x, y, a, b, yaw in rects
    ]
    shapes += [(RigidTransform([x, y, HEIGHT / 2]), Cylinder(r, HEIGHT)) for x, y, r in circles]
    shapes.append((RigidTransform([*STAR["centre"], 0.0]), Mesh(str(mesh_file))))
    for i, (X_WG, shape) in enumerate(shapes):
        plant.RegisterCollisionGeometry(world, X_WG, shape, f"g{i}", friction)
        plant.RegisterVisualGeometry(world, X_WG, shape, f"g{i}", [0.5, 0.5, 0.5, 1.0])
    robot = plant.AddModelInstance("robot")
    body = plant.AddRigidBody("base", robot, SpatialInertia.SolidBoxWithMass(1.0, 0.1, 0.1, 0.1))
    plant.Finalize()
    return builder, plant, scene_graph, body, robot


def exact_ranges(rects, circles, outline_W, xy, yaw, angles, range_max):
    """Exact horizontal ranges from (x, y) by brute force over segments and circles."""
    segments = []
    for x, y, a, b, th in rects:
        c, s = math.cos(th), math.sin(th)
        corners = [
            (x + c * u - s * v, y + s * u + c * v)
            for u, v in ((-a / 2, -b / 2), (a / 2, -b / 2), (a / 2, b / 2), (-a / 2, b / 2))
        ]
        segments += [(corners[i], corners[(i + 1) % 4]) for i in range(4)]
    segments += [(outline_W[i], outline_W[(i + 1) % len(outline_W)]) for i in range(len(outline_W))]
    seg = np.array(segments, dtype=float) - np.asarray(xy)
    d = np.column_stack([np.cos(angles + yaw), np.sin(angles + yaw)])
    a, e = seg[:, 0], seg[:, 1] - seg[:, 0]
    den = d[:, None, 0] * e[None, :, 1] - d[:, None, 1] * e[None, :, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (a[None, :, 0] * e[None, :, 1] - a[None, :, 1] * e[None, :, 0]) / den
        s = (a[None, :, 0] * d[:, None, 1] - a[None, :, 1] * d[:, None, 0]) / den
    t = np.where((s >= 0) & (s <= 1) & (t > 0), t, np.inf).min(axis=1)
    for cx, cy, r in circles:
        o = np.array([cx, cy]) - np.asarray(xy)
        b = d @ o
        disc = b * b - (o @ o - r * r)
        with np.errstate(invalid="ignore"):
            hit = b - np.sqrt(disc)
        t = np.minimum(t, np.where((disc >= 0) & (hit > 0), hit, np.inf))
    return np.where(t <= range_max, t, np.inf)


def depth_render_ranges(query_object, X_WL, angles, pixels, range_max):
    """Ranges read from four 90-degree depth renders about the lidar frame L's z axis."""
    info = CameraInfo(pixels, 3, pixels / 2, pixels / 2, pixels / 2 - 0.5 + 0.5, 1.0 + 0.5)
    core = RenderCameraCore("vtk", info, ClippingRange(0.01, range_max + 1), RigidTransform())
    camera = DepthRenderCamera(core, DepthRange(0.02, range_max + 0.5))
    ranges = np.full(len(angles), np.inf)
    # Columns: C's x (image right), y (image down), z (optical axis) in L, looking along L's x.
    R_forward = RotationMatrix(np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]))
    wrapped = (angles + np.pi / 4) % (2 * np.pi)  # camera k looks along k * 90 degrees
    for k in range(4):
        # Drake's camera frame C: z forward (L's direction k * 90 deg), x right, y down.
        R_LC = RotationMatrix.MakeZRotation(k * np.pi / 2) @ R_forward
        X_WC = X_WL @ RigidTransform(R_LC)
        image = query_object.RenderDepthImage(
            camera, query_object.inspector().world_frame_id(), X_WC
        )
        row = np.asarray(image.data)[1, :, 0].astype(float)
        mine = (wrapped >= k * np.pi / 2) & (wrapped < (k + 1) * np.pi / 2)
        phi = angles[mine] - k * np.pi / 2
        phi = (phi + np.pi) % (2 * np.pi) - np.pi
        u = np.clip(np.rint(pixels / 2 - 0.5 - (pixels / 2) * np.tan(phi)), 0, pixels - 1)
        x_n = (u - (pixels / 2 - 0.5)) / (pixels / 2)
        ranges[mine] = row[u.astype(int)] * np.sqrt(1.0 + x_n * x_n)
    return np.where(ranges <= range_max, ranges, np.inf)


def error_stats(measured, exact) -> dict:
    """|measured - exact| over the beams finite in both: max and 99th percentile (mm); the
    beams finite in one and not the other, and all the beams."""
    both = np.isfinite(measured) & np.isfinite(exact)
    err = np.abs(measured[both] - exact[both])
    return {
        "max_error_mm": float(err.max() * 1e3),
        "p99_error_mm": float(np.percentile(err, 99) * 1e3),
        "mismatched_beams": int(np.sum(np.isfinite(measured) != np.isfinite(exact))),
        "beams": len(exact),
    }


def errors(stats: dict) -> str:
    return (
        f"max {stats['max_error_mm']:.3g} mm, p99 {stats['p99_error_mm']:.3g} mm, "
        f"{stats['mismatched_beams']} of {stats['beams']} beams finite in one and not the other"
    )


COLUMNS = [
    ["method", "method", "", ""],
    ["median_ms", "median per scan", "ms", ".3f"],
    ["scans", "scans timed", "", "d"],
    ["max_error_mm", "largest error", "mm", ".3g"],
    ["p99_error_mm", "p99 error", "mm", ".3g"],
    ["mismatched_beams", "beams finite in one only", "", "d"],
    ["beams", "beams compared", "", "d"],
]
"""(key, header, unit, format) of the ``--json`` table's columns."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scans", type=int, default=300, help="timed scans per method")
    parser.add_argument("--boxes", type=int, default=30)
    parser.add_argument("--cylinders", type=int, default=8)
    parser.add_argument("--pixels", type=int, default=360, help="columns per depth camera")
    parser.add_argument("--json", type=output_file("figures file"), help="write the figures")
    args = parser.parse_args()
    print(f"machine: {platform.platform()}, {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cpus, python {platform.python_version()}")  # fmt: skip
    rng = np.random.default_rng(7)
    rects, circles = scene_layout(rng, args.boxes, args.cylinders)
    config = LidarConfig(noise_sigma=0.0)
    with tempfile.TemporaryDirectory() as folder:
        mesh_file = Path(folder) / "star.obj"
        outline = star_outline(STAR["points"], STAR["r_in"], STAR["r_out"])
        triangles = write_prism_obj(mesh_file, outline, HEIGHT)
        builder, plant, scene_graph, body, robot = build(rects, circles, mesh_file)
        sick = load_lidar_config(lidar_preset_file("sick_tim571"))
        lidar, sick_lidar = (
            builder.AddSystem(Lidar(plant=plant, frame=body.body_frame(), config=c, ignore=[robot]))
            for c in (config, sick)
        )
        for system in (lidar, sick_lidar):
            builder.Connect(scene_graph.get_query_output_port(), system.get_input_port())
        diagram = builder.Build()
        context = diagram.CreateDefaultContext()
        print(
            f"scene: {len(rects)} boxes (4 walls), {len(circles)} cylinders, a mesh of "
            f"{triangles} triangles; {config.samples} beams, range_max {config.range_max} m"
        )
        poses = [(-2.0, -1.5, 0.3), (0.5, 0.0, 1.0), (1.0, -0.9, -2.0), (-1.0, 1.5, 2.5)]
        angles = config.fan().angles()
        outline_W = outline + np.array(STAR["centre"])
        results = {"ray casting": [], "depth renders": []}
        times = {"ray casting": [], "depth renders": [], "scan_now": []}
        first_scan_ms = None
        for x, y, yaw in poses:
            X_WB = RigidTransform(RotationMatrix.MakeZRotation(yaw), [x, y, SCAN_Z])
            plant.SetFreeBodyPose(plant.GetMyMutableContextFromRoot(context), body, X_WB)
            lidar_context = lidar.GetMyContextFromRoot(context)
            query_object = lidar.get_input_port().Eval(lidar_context)
            exact = exact_ranges(rects, circles, outline_W, (x, y), yaw, angles, config.range_max)
            for _ in range(args.scans // len(poses)):
                start = time.perf_counter()
                cast = lidar.exact_ranges(lidar_context)
                elapsed = time.perf_counter() - start
                if first_scan_ms is None:
                    first_scan_ms = elapsed * 1e3
                else:
                    times["ray casting"].append(elapsed)
                start = time.perf_counter()
                lidar.scan_now(lidar_context)
                times["scan_now"].append(time.perf_counter() - start)
            results["ray casting"].append((cast, exact))
            for _ in range(max(3, args.scans // 20 // len(poses))):
                start = time.perf_counter()
                rendered = depth_render_ranges(
                    query_object, X_WB, angles, args.pixels, config.range_max
                )
                times["depth renders"].append(time.perf_counter() - start)
            results["depth renders"].append((rendered, exact))
        print(f"ray casting: first scan (builds the cache) {first_scan_ms:.2f} ms")
        rows = []
        for name in ("ray casting", "scan_now", "depth renders"):
            t = times[name]
            line = f"{name}: median {statistics.median(t) * 1e3:.3f} ms per scan ({len(t)} scans)"
            row = {"method": name, "median_ms": statistics.median(t) * 1e3, "scans": len(t)}
            if name in results:
                measured = np.concatenate([m for m, _ in results[name]])
                exact = np.concatenate([e for _, e in results[name]])
                row.update(error_stats(measured, exact))
                line += "; error " + errors(row)
            rows.append(row)
            print(line)
        sick_context, t = sick_lidar.GetMyContextFromRoot(context), []
        for _ in range(args.scans // 4):
            start = time.perf_counter()
            sick_lidar.exact_ranges(sick_context)
            t.append(time.perf_counter() - start)
        print(
            f"ray casting, sick_tim571 preset ({sick.samples} beams, {sick.range_max} m): "
            f"median {statistics.median(t) * 1e3:.3f} ms per scan"
        )
    rows[0]["method"] = "ray casting (Lidar.exact_ranges)"
    rows[1]["method"] = "scan_now (ray casting, noise, LaserScan)"
    rows[2]["method"] = f"depth renders (4 VTK cameras, {args.pixels} x 3 pixels)"
    sick_row = {"median_ms": statistics.median(t) * 1e3, "scans": len(t)}
    rows.append({"method": f"ray casting, sick_tim571 ({sick.samples} beams)", **sick_row})
    if args.json:
        scene = (
            f"{len(rects)} boxes (4 walls), {len(circles)} cylinders, a mesh of {triangles} "
            f"triangles; {config.samples} beams, range_max {config.range_max:g} m"
        )
        table = {
            "title": f"Per method, {len(poses)} poses: {scene}",
            "columns": COLUMNS,
            "rows": rows,
            "note": f"The first ray-cast scan (it builds the cache): {first_scan_ms:.0f} ms.",
        }
        result = {
            "settings": {"scans": args.scans, "pixels": args.pixels},
            "figures": {"ray_casting_ms": rows[0]["median_ms"], "first_scan_ms": first_scan_ms},
            "tables": [table],
        }
        write_atomic(args.json, json.dumps(result, indent=1) + "\n", "figures")


if __name__ == "__main__":
    main()
