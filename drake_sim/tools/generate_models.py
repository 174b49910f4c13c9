"""Generates the street world's meshes and textures into ``models/``.

Run ``python -m drake_sim.tools.generate_models`` to (re)write every generated file, or
``python -m drake_sim.tools.generate_models --check`` to regenerate them in memory and exit 1,
listing each file that differs from the one on disk (PNG files are compared by decoded pixels, text
files byte for byte). The generated files are committed, so a test runs ``--check`` to stop drift.

Everything is deterministic: geometry comes from the dimensions below and textures from
``np.random.default_rng`` with fixed seeds. Textures tile seamlessly (their noise is blurred
with a circular convolution) and are at most 256 x 256 pixels.

Frames: every model's origin is at the centre of its footprint on the ground (z = 0, z up).
"""

from __future__ import annotations

import argparse
import io
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image

from drake_sim.base.resources import models_dir

_INCH = 0.0254  # m


@dataclass(frozen=True)
class JerseyBarrierSpec:
    """The New Jersey concrete barrier's profile (symmetric about its centre plane)."""

    length: float = 3.0  # m, along the model's x axis
    base_width: float = 24 * _INCH  # m
    top_width: float = 6 * _INCH  # m
    height: float = 32 * _INCH  # m
    reveal_height: float = 3 * _INCH  # m, vertical face at the base
    break_height: float = 13 * _INCH  # m, where the 55 degree slope turns to 84 degrees
    lower_slope_run: float = 7 * _INCH  # m, horizontal run of the 55 degree slope

    def profile(self) -> np.ndarray:
        """Returns the cross-section as 8 (y, z) points in metres, counter-clockwise from +x.

        Index 3 and 6 are the slope breaks: points 0-3 + 6-7 bound the lower convex piece,
        points 3-6 the upper one.
        """
        half_base = self.base_width / 2
        break_half = half_base - self.lower_slope_run
        half_top = self.top_width / 2
        right = [(half_base, self.reveal_height), (break_half, self.break_height)]
        return np.array(
            [(-half_base, 0.0), (half_base, 0.0), *right, (half_top, self.height)]
            + [(-half_top, self.height), (-break_half, self.break_height)]
            + [(-half_base, self.reveal_height)]
        )


@dataclass(frozen=True)
class TrafficConeSpec:
    """A 28 inch traffic cone on a square base plate."""

    height: float = 0.70  # m, base plate bottom to tip
    base_size: float = 0.36  # m, side of the square base plate
    base_thickness: float = 0.03  # m
    bottom_radius: float = 0.14  # m, of the cone body at the top of the plate
    top_radius: float = 0.025  # m
    band: tuple[float, float] = (0.42, 0.55)  # m, the white reflective band's z range
    sides: int = 24  # facets around the visual mesh; the collision hull uses half


@dataclass(frozen=True)
class CardboardBoxSpec:
    """A closed shipping box, taped along its top and bottom seams."""

    size: tuple[float, float, float] = (0.40, 0.30, 0.30)  # m, x y z


class _ObjWriter:
    """Collects planar polygons (with optional UVs, normals, material) and writes OBJ text."""

    def __init__(self) -> None:
        self._lines: list[str] = []
        self._counts = [0, 0, 0]  # v, vt, vn written so far
        self._material: str | None = None

    def polygon(self, points, *, normal=None, uvs=None, material=None, normals=None) -> None:
        """Adds one convex polygon; its winding is made counter-clockwise about ``normal``.

        Args:
            points: (n, 3) corners in metres.
            normal: outward unit normal for the whole face, or None (then ``normals``).
            uvs: (n, 2) texture coordinates, or None.
            material: MTL material name, or None to keep the current one.
            normals: (n, 3) per-corner unit normals for smooth faces, or None.
        """
        points = np.asarray(points, dtype=float)
        outward = normal if normal is not None else np.mean(normals, axis=0)
        order = np.arange(len(points))
        if np.dot(np.cross(points[1] - points[0], points[2] - points[0]), outward) < 0:
            order = order[::-1]
        if material is not None and material != self._material:
            self._lines.append(f"usemtl {material}")
            self._material = material
        v0, t0, n0 = (c + 1 for c in self._counts)
        self._lines += [f"v {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}" for p in points[order]]
        if uvs is not None:
            self._lines += [f"vt {t[0]:.5f} {t[1]:.5f}" for t in np.asarray(uvs)[order]]
        if normal is not None:
            normals = np.tile(normal, (len(points), 1))
        if normals is not None:
            normals = np.asarray(normals) / np.linalg.norm(normals, axis=1, keepdims=True)
            self._lines += [f"vn {n[0]:.5f} {n[1]:.5f} {n[2]:.5f}" for n in normals[order]]
        corners = []
        for i in range(len(points)):
            t = "" if uvs is None else str(t0 + i)
            n = "" if normals is None else f"/{n0 + i}"
            corners.append(f"{v0 + i}/{t}{n}" if (t or n) else f"{v0 + i}")
        self._lines.append("f " + " ".join(corners))
        self._counts[0] += len(points)
        self._counts[1] += 0 if uvs is None else len(points)
        self._counts[2] += 0 if normals is None else len(points)

    def text(self, header: str, mtllib: str | None = None) -> bytes:
        """Returns the OBJ file contents."""
        head = [
            f"# {header}",
            "# Generated by `python -m drake_sim.tools.generate_models`; do not edit.",
        ]
        if mtllib:
            head.append(f"mtllib {mtllib}")
        return ("\n".join(head + self._lines) + "\n").encode()


def _mtl(materials: dict[str, tuple[tuple[float, float, float], str | None]]) -> bytes:
    """Returns MTL text for ``{name: (diffuse rgb in [0, 1], texture file or None)}``."""
    lines = ["# Generated by `python -m drake_sim.tools.generate_models`; do not edit."]
    for name, (kd, texture) in materials.items():
        lines += [f"newmtl {name}", "Ka 0.2 0.2 0.2", f"Kd {kd[0]:.3f} {kd[1]:.3f} {kd[2]:.3f}"]
        lines += ["Ks 0.05 0.05 0.05", "Ns 10", "d 1", "illum 2"]
        if texture:
            lines.append(f"map_Kd {texture}")
    return ("\n".join(lines) + "\n").encode()


def _extrude(writer: _ObjWriter, profile, length: float, caps, *, tile=None, material=None):
    """Extrudes a counter-clockwise (y, z) profile along x from -length/2 to length/2.

    Args:
        writer: where the faces go.
        profile: (n, 2) points in metres, counter-clockwise seen from +x.
        length: extrusion length in metres.
        caps: lists of profile indices, each a convex part of the end caps.
        tile: texture repeat length in metres (UVs in metres / tile), or None for no UVs.
        material: MTL material name or None.
    """
    profile = np.asarray(profile, dtype=float)
    x0, x1 = -length / 2, length / 2
    s = 0.0
    for i in range(len(profile)):
        a, b = profile[i], profile[(i + 1) % len(profile)]
        edge = b - a
        normal = np.array([0.0, edge[1], -edge[0]]) / np.linalg.norm(edge)
        quad = [(x0, *a), (x1, *a), (x1, *b), (x0, *b)]
        s1 = s + float(np.linalg.norm(edge))
        uvs = None if tile is None else np.array([(x0, s), (x1, s), (x1, s1), (x0, s1)]) / tile
        writer.polygon(quad, normal=normal, uvs=uvs, material=material)
        s = s1
    for x, sign in ((x0, -1.0), (x1, 1.0)):
        for part in caps:
            pts = [(x, *profile[j]) for j in part]
            uvs = None if tile is None else profile[part] / tile
            writer.polygon(pts, normal=np.array([sign, 0.0, 0.0]), uvs=uvs, material=material)


def _box(writer: _ObjWriter, size, *, center=(0.0, 0.0, 0.0), uv_rects=None, material=None):
    """Adds an axis-aligned box with outward normals.

    Args:
        writer: where the faces go.
        size: (x, y, z) side lengths in metres.
        center: (x, y, z) of the box centre in metres.
        uv_rects: {face: (u0, v0, u1, v1)} texture rectangle per face ("+x", "-x", "+y", "-y",
            "+z", "-z"); faces map their first in-plane axis (cyclically after the normal's)
            to v and the second to u, so the top's texture v runs along x.
        material: MTL material name or None.
    """
    half = np.asarray(size, dtype=float) / 2
    for axis in range(3):
        for sign, tag in ((1.0, "+"), (-1.0, "-")):
            a, b = (axis + 1) % 3, (axis + 2) % 3
            corners = []
            for ca, cb in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = np.zeros(3)
                p[axis], p[a], p[b] = sign * half[axis], ca * half[a], cb * half[b]
                corners.append(p + np.asarray(center, dtype=float))
            normal = np.zeros(3)
            normal[axis] = sign
            uvs = None
            if uv_rects is not None:
                u0, v0, u1, v1 = uv_rects[tag + "xyz"[axis]]
                ab = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
                uvs = [
                    (u0 + (u1 - u0) * (cb + 1) / 2, v0 + (v1 - v0) * (ca + 1) / 2) for ca, cb in ab
                ]
            writer.polygon(corners, normal=normal, uvs=uvs, material=material)


def _frustum(writer: _ObjWriter, z0, z1, r0, r1, sides, *, material=None, cap=True) -> None:
    """Adds a smooth-shaded frustum about the z axis from (z0, radius r0) to (z1, r1), metres."""
    angles = 2 * np.pi * np.arange(sides + 1) / sides
    slope = (r0 - r1) / (z1 - z0)
    for k in range(sides):
        ring = [(angles[k], z0, r0), (angles[k + 1], z0, r0)]
        ring += [(angles[k + 1], z1, r1), (angles[k], z1, r1)]
        pts = [(r * np.cos(t), r * np.sin(t), z) for t, z, r in ring]
        normals = [(np.cos(t), np.sin(t), slope) for t, _, _ in ring]
        writer.polygon(pts, normals=normals, material=material)
    if cap:
        top = [(r1 * np.cos(t), r1 * np.sin(t), z1) for t in angles[:-1]]
        writer.polygon(top, normal=np.array([0.0, 0.0, 1.0]), material=material)
        bottom = [(r0 * np.cos(t), r0 * np.sin(t), z0) for t in angles[:-1]]
        writer.polygon(bottom, normal=np.array([0.0, 0.0, -1.0]), material=material)


def _periodic_noise(rng: np.random.Generator, shape, sigma: float) -> np.ndarray:
    """Returns zero-mean unit-variance noise blurred by a Gaussian of ``sigma`` pixels that
    tiles seamlessly (circular convolution through the FFT)."""
    white = rng.random(shape) - 0.5
    fy = np.fft.fftfreq(shape[0])[:, None]
    fx = np.fft.fftfreq(shape[1])[None, :]
    kernel = np.exp(-2 * (np.pi * sigma) ** 2 * (fx**2 + fy**2))
    field = np.real(np.fft.ifft2(np.fft.fft2(white) * kernel))
    return (field - field.mean()) / field.std()


def _to_rgb(grey: np.ndarray, tint) -> np.ndarray:
    """Returns uint8 RGB pixels: ``grey`` (0..255 scale) multiplied per channel by ``tint``."""
    rgb = grey[..., None] * np.asarray(tint, dtype=float)[None, None, :]
    return np.clip(np.round(rgb), 0, 255).astype(np.uint8)


def asphalt_texture(size: int = 128, seed: int = 11) -> np.ndarray:
    """Returns a dark grey grainy asphalt texture (uint8 RGB, tiles seamlessly)."""
    rng = np.random.default_rng(seed)
    grey = (
        66
        + 6 * _periodic_noise(rng, (size, size), 6.0)
        + 9 * _periodic_noise(rng, (size, size), 0.6)
    )
    specks = rng.random((size, size))
    grey = np.where(specks > 0.985, grey + 32, np.where(specks < 0.02, grey - 18, grey))
    return _to_rgb(grey, (1.0, 1.0, 1.03))


def concrete_texture(size: int = 128, seed: int = 12) -> np.ndarray:
    """Returns a light grey, subtly mottled and pitted concrete texture (uint8 RGB)."""
    rng = np.random.default_rng(seed)
    grey = (
        172
        + 4 * _periodic_noise(rng, (size, size), 10.0)
        + 4 * _periodic_noise(rng, (size, size), 0.7)
    )
    pores = _periodic_noise(rng, (size, size), 0.8)
    grey = np.where(pores > 2.6, grey - 40, grey)
    return _to_rgb(grey, (1.0, 0.985, 0.95))


def cardboard_texture(size: int = 256, seed: int = 13) -> np.ndarray:
    """Returns a cardboard texture atlas (uint8 RGB).

    The left half (u < 0.5) is plain board; the right half has a strip of brown packing tape
    centred on u = 0.75 running along v, 0.25 of the half-width wide.
    """
    rng = np.random.default_rng(seed)
    shade = 1.0 + 0.04 * _periodic_noise(rng, (size, size), 8.0)
    shade += 0.025 * _periodic_noise(rng, (size, size), 0.7)
    rows = np.arange(size)[:, None]
    shade += 0.015 * np.cos(2 * np.pi * rows / 6.0)  # faint flutes of the corrugation
    rgb = shade[..., None] * np.array([176.0, 132.0, 84.0])
    u = (np.arange(size)[None, :] + 0.5) / size
    tape = np.abs(u - 0.75) < 0.0625
    tape_rgb = (0.97 + 0.03 * _periodic_noise(rng, (size, size), 20.0))[..., None]
    tape_rgb = tape_rgb * np.array([196.0, 150.0, 96.0])
    rgb = np.where(tape[..., None], tape_rgb, rgb)
    edge = (np.abs(u - 0.75) > 0.058) & tape
    rgb = np.where(edge[..., None], rgb * 0.85, rgb)
    return np.clip(np.round(rgb), 0, 255).astype(np.uint8)


def _barrier_files(spec: JerseyBarrierSpec) -> dict[str, bytes | np.ndarray]:
    """Returns the barrier's visual OBJ/MTL/PNG and its two convex collision OBJs."""
    profile = spec.profile()
    lower, upper = [0, 1, 2, 3, 6, 7], [3, 4, 5, 6]
    visual = _ObjWriter()
    _extrude(visual, profile, spec.length, [lower, upper], tile=1.0, material="concrete")
    files: dict[str, bytes | np.ndarray] = {
        "jersey_barrier.obj": visual.text("New Jersey barrier, visual", "jersey_barrier.mtl"),
        "jersey_barrier.mtl": _mtl({"concrete": ((1.0, 1.0, 1.0), "concrete.png")}),
        "concrete.png": concrete_texture(),
    }
    for name, part in (("lower", lower), ("upper", upper)):
        piece = _ObjWriter()
        _extrude(piece, profile[part], spec.length, [list(range(len(part)))])
        files[f"jersey_barrier_{name}.obj"] = piece.text(f"New Jersey barrier, {name} convex piece")
    return files


def _cone_files(spec: TrafficConeSpec) -> dict[str, bytes | np.ndarray]:
    """Returns the traffic cone's visual OBJ/MTL (orange, white band, black base) and its
    convex collision hull of the cone body (the base plate collides as an SDF box)."""
    visual = _ObjWriter()
    plate = (spec.base_size, spec.base_size, spec.base_thickness)
    _box(visual, plate, center=(0.0, 0.0, spec.base_thickness / 2), material="base")
    z0, z1, zb0, zb1 = spec.base_thickness, spec.height, *spec.band
    radius = np.interp([zb0, zb1], [z0, z1], [spec.bottom_radius, spec.top_radius])
    _frustum(
        visual, z0, zb0, spec.bottom_radius, radius[0], spec.sides, material="orange", cap=False
    )
    _frustum(visual, zb0, zb1, radius[0], radius[1], spec.sides, material="white", cap=False)
    _frustum(visual, zb1, z1, radius[1], spec.top_radius, spec.sides, material="orange")
    collision = _ObjWriter()
    _frustum(collision, z0, z1, spec.bottom_radius, spec.top_radius, spec.sides // 2)
    return {
        "traffic_cone.obj": visual.text("Traffic cone, visual", "traffic_cone.mtl"),
        "traffic_cone.mtl": _mtl(
            {
                "base": ((0.08, 0.08, 0.08), None),
                "orange": ((1.0, 0.36, 0.02), None),
                "white": ((0.95, 0.95, 0.95), None),
            }
        ),
        "traffic_cone_body.obj": collision.text("Traffic cone body, convex collision hull"),
    }


def _box_files(spec: CardboardBoxSpec) -> dict[str, bytes | np.ndarray]:
    """Returns the cardboard box's visual OBJ/MTL/PNG; the tape runs along x over the top,
    down both ends and along the bottom (the box collides as an SDF box)."""
    plain, taped = (0.0, 0.0, 0.5, 1.0), (0.5, 0.0, 1.0, 1.0)
    rects = {"+x": taped, "-x": taped, "+y": plain, "-y": plain, "+z": taped, "-z": taped}
    visual = _ObjWriter()
    _box(visual, spec.size, center=(0.0, 0.0, spec.size[2] / 2), uv_rects=rects, material="board")
    return {
        "cardboard_box.obj": visual.text("Cardboard box, visual", "cardboard_box.mtl"),
        "cardboard_box.mtl": _mtl({"board": ((1.0, 1.0, 1.0), "cardboard.png")}),
        "cardboard.png": cardboard_texture(),
    }


def _ground_files(size: float = 30.0, tile: float = 2.0) -> dict[str, bytes | np.ndarray]:
    """Returns the asphalt ground's visual: a ``size`` x ``size`` m quad with its top at z = 0
    whose texture repeats every ``tile`` m."""
    half = size / 2
    quad = np.array(
        [(-half, -half, 0.0), (half, -half, 0.0), (half, half, 0.0), (-half, half, 0.0)]
    )
    visual = _ObjWriter()
    visual.polygon(
        quad, normal=np.array([0.0, 0.0, 1.0]), uvs=quad[:, :2] / tile, material="asphalt"
    )
    return {
        "asphalt_ground.obj": visual.text("Asphalt ground, visual", "asphalt_ground.mtl"),
        "asphalt_ground.mtl": _mtl({"asphalt": ((1.0, 1.0, 1.0), "asphalt.png")}),
        "asphalt.png": asphalt_texture(),
    }


def generate(models_root: Path) -> dict[Path, bytes | np.ndarray]:
    """Returns every generated file: its path under ``models_root`` and its contents (bytes
    for text files, a uint8 RGB array for PNG images)."""
    groups = {
        "jersey_barrier": _barrier_files(JerseyBarrierSpec()),
        "traffic_cone": _cone_files(TrafficConeSpec()),
        "cardboard_box": _box_files(CardboardBoxSpec()),
        "asphalt_ground": _ground_files(),
    }
    root = Path(models_root)
    return {root / d / name: data for d, files in groups.items() for name, data in files.items()}


def write(files: dict[Path, bytes | np.ndarray]) -> None:
    """Writes ``files`` (as returned by ``generate``), creating folders as needed."""
    for path, data in files.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(data, np.ndarray):
            buffer = io.BytesIO()
            Image.fromarray(data).save(buffer, format="PNG", optimize=True)
            data = buffer.getvalue()
        path.write_bytes(data)


def differences(files: dict[Path, bytes | np.ndarray]) -> list[Path]:
    """Returns the paths in ``files`` whose file on disk is missing or differs (PNG images
    are compared by decoded pixels, other files byte for byte)."""
    stale = []
    for path, data in files.items():
        if not path.is_file():
            stale.append(path)
        elif isinstance(data, np.ndarray):
            with Image.open(path) as image:
                pixels = np.asarray(image.convert("RGB"))
            if pixels.shape != data.shape or not np.array_equal(pixels, data):
                stale.append(path)
        elif path.read_bytes() != data:
            stale.append(path)
    return stale


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point; returns the exit code."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--check", action="store_true", help="exit 1 if any generated file on disk differs"
    )
    parser.add_argument("--models", type=Path, default=None, help="models folder to write")
    args = parser.parse_args(argv)
    root = args.models or models_dir()
    files = generate(root)
    if args.check:
        stale = differences(files)
        for path in stale:
            print(f"out of date: {path.relative_to(root)}", file=sys.stderr)
        return 1 if stale else 0
    write(files)
    print(f"wrote {len(files)} files under {root}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
