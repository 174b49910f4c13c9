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

import io
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image

from drake_sim.base import cli
from drake_sim.base.obj_mesh import ObjWriter, box, extrude, frustum, mtl
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
    visual = ObjWriter()
    extrude(visual, profile, spec.length, [lower, upper], tile=1.0, material="concrete")
    files: dict[str, bytes | np.ndarray] = {
        "jersey_barrier.obj": visual.text("New Jersey barrier, visual", "jersey_barrier.mtl"),
        "jersey_barrier.mtl": mtl({"concrete": ((1.0, 1.0, 1.0), "concrete.png")}),
        "concrete.png": concrete_texture(),
    }
    for name, part in (("lower", lower), ("upper", upper)):
        piece = ObjWriter()
        extrude(piece, profile[part], spec.length, [list(range(len(part)))])
        files[f"jersey_barrier_{name}.obj"] = piece.text(f"New Jersey barrier, {name} convex piece")
    return files


def _cone_files(spec: TrafficConeSpec) -> dict[str, bytes | np.ndarray]:
    """Returns the traffic cone's visual OBJ/MTL (orange, white band, black base) and its
    convex collision hull of the cone body (the base plate collides as an SDF box)."""
    visual = ObjWriter()
    plate = (spec.base_size, spec.base_size, spec.base_thickness)
    box(visual, plate, center=(0.0, 0.0, spec.base_thickness / 2), material="base")
    z0, z1, zb0, zb1 = spec.base_thickness, spec.height, *spec.band
    radius = np.interp([zb0, zb1], [z0, z1], [spec.bottom_radius, spec.top_radius])
    frustum(
        visual, z0, zb0, spec.bottom_radius, radius[0], spec.sides, material="orange", cap=False
    )
    frustum(visual, zb0, zb1, radius[0], radius[1], spec.sides, material="white", cap=False)
    frustum(visual, zb1, z1, radius[1], spec.top_radius, spec.sides, material="orange")
    collision = ObjWriter()
    frustum(collision, z0, z1, spec.bottom_radius, spec.top_radius, spec.sides // 2)
    return {
        "traffic_cone.obj": visual.text("Traffic cone, visual", "traffic_cone.mtl"),
        "traffic_cone.mtl": mtl(
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
    visual = ObjWriter()
    box(visual, spec.size, center=(0.0, 0.0, spec.size[2] / 2), uv_rects=rects, material="board")
    return {
        "cardboard_box.obj": visual.text("Cardboard box, visual", "cardboard_box.mtl"),
        "cardboard_box.mtl": mtl({"board": ((1.0, 1.0, 1.0), "cardboard.png")}),
        "cardboard.png": cardboard_texture(),
    }


def _ground_files(size: float = 30.0, tile: float = 2.0) -> dict[str, bytes | np.ndarray]:
    """Returns the asphalt ground's visual: a ``size`` x ``size`` m quad with its top at z = 0
    whose texture repeats every ``tile`` m."""
    half = size / 2
    quad = np.array(
        [(-half, -half, 0.0), (half, -half, 0.0), (half, half, 0.0), (-half, half, 0.0)]
    )
    visual = ObjWriter()
    visual.polygon(
        quad, normal=np.array([0.0, 0.0, 1.0]), uvs=quad[:, :2] / tile, material="asphalt"
    )
    return {
        "asphalt_ground.obj": visual.text("Asphalt ground, visual", "asphalt_ground.mtl"),
        "asphalt_ground.mtl": mtl({"asphalt": ((1.0, 1.0, 1.0), "asphalt.png")}),
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
    parser = cli.ArgumentParser(
        prog="python -m drake_sim.tools.generate_models", description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "--check", action="store_true", help="exit 1 if any generated file on disk differs"
    )
    parser.add_argument("--models", type=cli.output_dir("models folder"), help="folder to write")
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
    sys.exit(cli.run(main))
