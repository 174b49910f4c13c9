"""``python -m drake_sim.tools.map_info MAP.yaml [--arena FILE] [--show]``: what a map_server map
holds, and how it compares with an arena.

Loads the map with map_server's rules (``load_map``) and prints its size, resolution, origin and
cell counts; with ``--arena`` also the map's IoU and known fraction against the arena's ground
truth at the lidar's scan height (the scores ``python -m drake_sim.mapping`` reports); with
``--show`` draws it in Meshcat (with the arena, when given) until Ctrl-C. A missing, unreadable
or malformed map file is one line on stderr and exit code 2.
"""

import sys
import time

from pydrake.geometry import MeshcatVisualizer, StartMeshcat
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.systems.framework import DiagramBuilder

from drake_sim.base import cli
from drake_sim.base.map_files import OccupancyMap, load_map
from drake_sim.robots.turtlebot3 import default_turtlebot3_file
from drake_sim.robots.turtlebot3_params import load_turtlebot3_params
from drake_sim.systems.estimation.occupancy_grid import known_fraction, occupancy_iou
from drake_sim.systems.viewer.map_view import map_mesh
from drake_sim.worlds.arena import arena_grid, load_arena
from drake_sim.worlds.arena_world import add_arena

SHOW_PERIOD = 0.1
"""s between checks for Ctrl-C while the map is shown."""


def _parse_args(argv):
    parser = cli.ArgumentParser(
        prog="python -m drake_sim.tools.map_info", description=__doc__.split("\n")[0]
    )
    parser.add_argument("map", type=cli.input_file("map file"), help="map_server .yaml")
    parser.add_argument("--arena", type=cli.input_file("arena file"), help="arena YAML")
    parser.add_argument(
        "--robot",
        type=cli.input_file("robot file"),
        default=default_turtlebot3_file(),
        help="robot YAML (its lidar's height picks the arena's obstacles that count)",
    )
    parser.add_argument("--show", action="store_true", help="draw the map in Meshcat")
    return parser.parse_args(argv)


def describe(occupancy_map: OccupancyMap) -> str:
    """One line: size in cells and metres, resolution, origin and the cells of each kind."""
    rows, cols = occupancy_map.shape
    x, y, yaw = occupancy_map.origin
    return (
        f"{cols} x {rows} cells ({occupancy_map.width_m:.2f} x {occupancy_map.height_m:.2f} m) "
        f"at {occupancy_map.resolution:g} m, origin ({x:.3f}, {y:.3f}, {yaw:.3f}); "
        f"{int(occupancy_map.free().sum())} free, {int(occupancy_map.occupied().sum())} "
        f"occupied, {int(occupancy_map.unknown().sum())} unknown"
    )


def main(argv=None) -> int:
    args = _parse_args(argv)
    occupancy_map = load_map(args.map)
    print(f"{args.map}: {describe(occupancy_map)}")
    arena = load_arena(args.arena) if args.arena is not None else None
    if arena is not None:
        height = load_turtlebot3_params(args.robot).scan_height
        truth = arena_grid(arena, occupancy_map.resolution, height=height)
        print(
            f"against {args.arena.name}: map IoU {occupancy_iou(occupancy_map, truth):.3f}, "
            f"known {100 * known_fraction(occupancy_map, truth):.1f} %"
        )
    if args.show:
        _show(occupancy_map, arena)
    return cli.EXIT_OK


def _show(occupancy_map: OccupancyMap, arena) -> None:
    meshcat = StartMeshcat()
    meshcat.SetProperty("/Grid", "visible", False)
    if arena is not None:
        builder = DiagramBuilder()
        plant, scene_graph = AddMultibodyPlant(MultibodyPlantConfig(), builder)
        add_arena(plant, arena)
        plant.Finalize()
        MeshcatVisualizer.AddToBuilder(builder, scene_graph, meshcat)
        diagram = builder.Build()
        diagram.ForcedPublish(diagram.CreateDefaultContext())
    meshcat.SetTriangleColorMesh("/map", *map_mesh(occupancy_map))
    cli.announce(meshcat, "showing the map")
    try:
        while True:
            time.sleep(SHOW_PERIOD)
    except BaseException as e:
        if not cli.is_stop(e):
            raise


if __name__ == "__main__":
    sys.exit(cli.run(main))
