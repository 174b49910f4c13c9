"""``python -m drake_sim.tools.readme_pictures``: (re)makes the README's pictures under
``docs/images/``.

* ``flip.gif``: a short headless ``python -m drake_sim.flip --record`` run, replayed in
  headless Chromium and assembled into a GIF (``drake_sim.tools.replay_frames``).
* ``flip_diagram.svg`` and ``panda_station_diagram.svg``: the flip diagram (on bare ground: the
  street's props add only unconnected plant ports) and the Panda station (physics mode), drawn
  by Drake's ``GetGraphvizString`` and Graphviz's ``dot``.
* ``pickplace.gif``: the same as ``flip.gif`` for ``python -m drake_sim.pickplace``, made only
  when that module exists (skipped with a message until then).
* ``walle.gif``: the same for ``python -m drake_sim.walle`` in ``both`` mode on the oval course
  (``WALLE_GIF``, ``make_walle_gif``).
* ``mapping.gif``: the same for ``python -m drake_sim.mapping`` on the room's default route
  (``MAPPING_GIF``, ``make_mapping_gif``): the map grows as the robot drives.
* ``navigation.gif``: ``python -m drake_sim.navigate`` on the room's ground-truth map with a box
  the map does not have (``NAVIGATION_GIF``, ``make_navigation_gif``).

``--only NAME ...`` makes a subset (``flip``, ``diagrams``, ``pickplace``, ``walle``,
``mapping``, ``navigation``). Exit code 2 with
one line on stderr when ``dot`` or Chromium is missing for a picture that needs it.
"""

from __future__ import annotations

import dataclasses as dc
import importlib.util
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path

from diagrams.arm_station import make_arm_station_diagram
from diagrams.flip import make_flip_diagram
from diagrams.flip_scenario import load_flip_scenario
from diagrams.pickplace_scenario import load_pickplace_scenario
from drake_sim.base import cli
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import save_map
from drake_sim.base.resources import config_dir
from drake_sim.robots.ddrive import default_robot_file
from drake_sim.robots.ddrive_params import load_robot_params
from drake_sim.robots.turtlebot3 import default_turtlebot3_file
from drake_sim.robots.turtlebot3_params import load_turtlebot3_params
from drake_sim.tools.browser import find_chromium
from drake_sim.tools.replay_frames import capture_replay, save_gif
from drake_sim.worlds.arena import arena_grid, load_arena

IMAGES_DIR = Path(__file__).resolve().parents[2] / "docs" / "images"
"""Where the pictures go: ``docs/images/`` of the checkout."""


@dc.dataclass(frozen=True)
class GifSpec:
    """How to turn one entry point's replay into a GIF.

    The entry point is run as ``python -m <module> --headless --record REPLAY.html <args>``.
    """

    module: str  # e.g. "drake_sim.flip"
    args: tuple[str, ...] = ()  # more options for the run (its duration, seed, ...)
    frames: int = 80  # pictures, evenly spaced over the replay
    fps: float = 10.0  # GIF playback rate; frames / fps = the GIF's length (s)
    size: tuple[int, int] = (640, 400)  # pixels
    camera: tuple[float, ...] | None = None  # [x, y, z, tx, ty, tz] (m); None: the recording's


FLIP_GIF = GifSpec("drake_sim.flip", ("--duration", "8", "--seed", "0"))
"""Eight simulated seconds (four flips) played in real time."""

PICKPLACE_GIF = GifSpec(
    "drake_sim.pickplace",
    ("--mode", "physics", "--seed", "0"),
    frames=60,
    camera=(1.3, -0.45, 0.75, 0.35, 0.0, 0.2),
)
"""The pick-and-place task, once ``drake_sim.pickplace`` exists."""

WALLE_GIF = GifSpec(
    "drake_sim.walle",
    (
        "--mode",
        "both",
        "--course",
        str(config_dir() / "courses" / "oval.yaml"),
        "--duration",
        "12",
        "--seed",
        "0",
    ),
    frames=120,
    size=(640, 360),
    camera=(0.75, -0.85, 1.15, 0.75, 0.5, 0.0),
)
"""Wall-E balancing round the oval's first straight and turn: 12 simulated seconds played in
real time."""


def need_dot() -> str:
    """Returns the path of Graphviz's ``dot``.

    Raises:
        ConfigError: when it is not installed (says how to install it).
    """
    dot = shutil.which("dot")
    if dot is None:
        raise ConfigError(
            "Graphviz's `dot` not found: install it (`apt-get install graphviz`) to draw diagrams"
        )
    return dot


def render_graphviz(dot_source: str, out: Path) -> Path:
    """Renders Graphviz source to ``out``, in the format its suffix names (``.svg``,
    ``.png``).

    Raises:
        ConfigError: when ``dot`` is missing.
        RuntimeError: when ``dot`` fails.
    """
    dot = need_dot()
    out.parent.mkdir(parents=True, exist_ok=True)
    fmt = out.suffix.lstrip(".") or "svg"
    done = subprocess.run(
        [dot, f"-T{fmt}", "-o", str(out)], input=dot_source, text=True, capture_output=True
    )
    if done.returncode != 0:
        raise RuntimeError(f"dot failed on {out.name}: {done.stderr.strip()}")
    return out


def flip_diagram_graphviz(max_depth: int = 1) -> str:
    """Graphviz source of the flip diagram (``config/flip.yaml`` on bare ground)."""
    scenario = load_flip_scenario(config_dir() / "flip.yaml")
    scenario = dc.replace(scenario, scene=dc.replace(scenario.scene, world=""))
    diagram = make_flip_diagram(scenario, load_robot_params(default_robot_file()))
    return diagram.GetGraphvizString(max_depth=max_depth)


def panda_station_graphviz(max_depth: int = 1) -> str:
    """Graphviz source of the Panda station in physics mode (the shipped scenario)."""
    diagram = make_arm_station_diagram(load_pickplace_scenario().station_config(), mode="physics")
    return diagram.GetGraphvizString(max_depth=max_depth)


MAPPING_GIF = GifSpec(
    "drake_sim.mapping",
    ("--arena", str(config_dir() / "arenas" / "room.yaml"), "--seed", "0"),
    frames=120,
    fps=12.0,
    size=(640, 480),
    camera=(0.0, -2.0, 7.5, 0.0, -0.2, 0.0),
)
"""The room mapped along its default route (about two simulated minutes), seen from above."""


NAVIGATION_GIF = GifSpec(
    "drake_sim.navigate",
    (
        "--goals",
        str(config_dir() / "goals" / "room.yaml"),
        "--initial-pose",
        "-1.8",
        "-1.5",
        "30",
        "--set",
        "extra_obstacles=[{box: {size: [0.4, 0.6, 0.3], position: [0.3, -1.8]}}]",
        "--seed",
        "0",
    ),
    frames=120,
    fps=12.0,
    size=(640, 480),
    camera=(0.0, -2.0, 7.5, 0.0, -0.2, 0.0),
)
"""The room's goals from a first guess 0.45 m and 30 degrees off, round a box the map does not
have; ``make_navigation_gif`` adds ``--map`` (the room's ground truth, saved for the run)."""


def record_replay(module: str, html: Path, args: Sequence[str] = ()) -> Path:
    """Runs ``python -m <module> --headless --record <html> <args>`` and returns ``html``.

    Raises:
        RuntimeError: when the run fails (with its last stderr line).
    """
    command = [sys.executable, "-m", module, "--headless", "--record", str(html), *args]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0 or not html.is_file():
        last = (done.stderr.strip().splitlines() or ["no output"])[-1]
        raise RuntimeError(f"python -m {module} failed (exit {done.returncode}): {last}")
    return html


def replay_gif(spec: GifSpec, out: Path) -> Path:
    """Records ``spec.module`` headless and writes its replay as a GIF to ``out``."""
    with tempfile.TemporaryDirectory(prefix="drake_sim_pictures_") as tmp:
        html = record_replay(spec.module, Path(tmp) / "replay.html", spec.args)
        pictures = capture_replay(html, frames=spec.frames, size=spec.size, camera=spec.camera)
    save_gif(pictures, out, fps=spec.fps)
    return out


def make_flip_gif(images: Path) -> list[Path]:
    """``flip.gif``."""
    return [replay_gif(FLIP_GIF, images / "flip.gif")]


def make_diagrams(images: Path) -> list[Path]:
    """``flip_diagram.svg`` and ``panda_station_diagram.svg``."""
    need_dot()  # Before building anything.
    return [
        render_graphviz(flip_diagram_graphviz(), images / "flip_diagram.svg"),
        render_graphviz(panda_station_graphviz(), images / "panda_station_diagram.svg"),
    ]


def make_pickplace_gif(images: Path) -> list[Path]:
    """``pickplace.gif``, or nothing (with a message) while ``drake_sim.pickplace`` is missing."""
    if importlib.util.find_spec(PICKPLACE_GIF.module) is None:
        print(f"skipped pickplace.gif: {PICKPLACE_GIF.module} does not exist yet")
        return []
    return [replay_gif(PICKPLACE_GIF, images / "pickplace.gif")]


def make_walle_gif(images: Path) -> list[Path]:
    """``walle.gif``."""
    return [replay_gif(WALLE_GIF, images / "walle.gif")]


def make_mapping_gif(images: Path) -> list[Path]:
    """``mapping.gif`` (the run's map files go to a temporary folder)."""
    with tempfile.TemporaryDirectory(prefix="drake_sim_map_") as tmp:
        spec = dc.replace(MAPPING_GIF, args=(*MAPPING_GIF.args, "--out", str(Path(tmp) / "room")))
        return [replay_gif(spec, images / "mapping.gif")]


def make_navigation_gif(images: Path) -> list[Path]:
    """``navigation.gif``, on the room's ground-truth map saved as map_server files."""
    robot = load_turtlebot3_params(default_turtlebot3_file())
    arena = load_arena(config_dir() / "arenas" / "room.yaml")
    with tempfile.TemporaryDirectory(prefix="drake_sim_map_") as tmp:
        truth = arena_grid(arena, 0.05, height=robot.scan_height)
        _, yaml_file = save_map(truth, Path(tmp) / "room")
        spec = dc.replace(NAVIGATION_GIF, args=("--map", str(yaml_file), *NAVIGATION_GIF.args))
        return [replay_gif(spec, images / "navigation.gif")]


PICTURES: dict[str, Callable[[Path], list[Path]]] = {
    "flip": make_flip_gif,
    "diagrams": make_diagrams,
    "pickplace": make_pickplace_gif,
    "walle": make_walle_gif,
    "mapping": make_mapping_gif,
    "navigation": make_navigation_gif,
}
"""Each picture group and the function that writes it into a folder."""

_NEEDS_CHROMIUM = ("flip", "pickplace", "walle", "mapping", "navigation")


def _parse_args(argv):
    parser = cli.ArgumentParser(
        prog="python -m drake_sim.tools.readme_pictures", description=__doc__.split("\n")[0]
    )
    parser.add_argument(
        "--out", type=cli.output_dir("picture folder"), default=IMAGES_DIR, help="folder to write"
    )
    parser.add_argument(
        "--only", nargs="+", choices=sorted(PICTURES), default=list(PICTURES), help="a subset"
    )
    return parser.parse_args(argv)


def main(argv=None) -> int:
    args = _parse_args(argv)
    if "diagrams" in args.only:
        need_dot()
    if set(args.only) & set(_NEEDS_CHROMIUM) and find_chromium() is None:
        raise ConfigError("no Chromium found for the GIFs: install it (apt-get install chromium)")
    for name in args.only:
        for path in PICTURES[name](args.out):
            print(f"wrote {path} ({path.stat().st_size / 1024:.0f} KiB)")
    return cli.EXIT_OK


if __name__ == "__main__":
    sys.exit(cli.run(main))
