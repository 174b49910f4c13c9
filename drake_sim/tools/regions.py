"""Precomputes the IRIS regions of a pick-and-place scene into the cache
(``planning.search.iris_regions``).

Usage::

    python -m drake_sim.tools.regions --scene config/pickplace.yaml [--named ready ...]
        [--no-pick-place] [--seeds FILE] [--options FILE] [--set key=value ...]

Seeds, in route order: the named configurations (default "ready"), then, unless
``--no-pick-place``, the pre-grasp and pre-place configurations (the hand pointing down
``--approach-height`` m above the scene's object and place target, by IK), then the rows of
``--seeds FILE`` (YAML: a list of 7-joint lists, rad). ``--options FILE`` is a YAML of
``RegionOptions``. Prints one line per region (a tqdm bar when tqdm is installed) and a summary.
Exit code 0 on success, 1 when the regions cannot be grown, 2 on bad input (one stderr line).
"""

import sys
import time
from pathlib import Path

import numpy as np

from drake_sim.base.cli import ArgumentParser, input_file, positive_float, run
from drake_sim.base.errors import ConfigError


def pick_place_seeds(scene, state, height: float) -> list[np.ndarray]:
    """Pre-grasp and pre-place arm configurations (rad): the hand pointing down, ``height`` m
    above the scene's "object" and ``place_position`` (those present), by IK from "ready"."""
    from pydrake.math import RigidTransform, RotationMatrix

    R_WE = RotationMatrix.MakeXRotation(np.pi)  # hand z axis pointing down
    targets = []
    if scene.has_object("object"):
        targets.append(scene.object_pose("object").translation())
    if scene.place_position is not None:
        targets.append(np.asarray(scene.place_position))
    ready = state.named("ready")
    return [state.ik(RigidTransform(R_WE, p + [0, 0, height]), q_seed=ready).q for p in targets]


def _progress():
    """Returns (callback taking one line, close function): tqdm when installed, else print."""
    try:
        from tqdm import tqdm
    except ImportError:
        return (lambda line: print(line, file=sys.stderr, flush=True)), (lambda: None)
    bars = []  # made at the first region: nothing is shown when the regions are loaded

    def step(line: str) -> None:
        if not bars:
            bars.append(tqdm(unit="region", file=sys.stderr))
        bars[0].update(1)
        bars[0].set_postfix_str(line)

    return step, lambda: [bar.close() for bar in bars]


def _load_options(args):
    import dataclasses as dc

    import yaml
    from pydrake.common.yaml import yaml_load_typed

    from planning.search.iris_regions import RegionOptions, check_region_options

    errors = (RuntimeError, ValueError, TypeError, yaml.YAMLError, OSError)
    options = RegionOptions()
    if args.options is not None:
        try:
            options = yaml_load_typed(schema=RegionOptions, filename=str(args.options))
        except errors as e:
            raise ConfigError(f"--options {args.options}: {' '.join(str(e).split())}") from e
    for item in args.set:
        key, _, value = item.partition("=")
        if key not in {f.name for f in dc.fields(RegionOptions)} or not value:
            raise ConfigError(f"--set {item!r}: not key=value with a RegionOptions key")
        try:
            options = yaml_load_typed(
                schema=RegionOptions, data=f"{key}: {value}", defaults=options
            )
        except errors as e:
            raise ConfigError(f"--set {item!r}: {' '.join(str(e).split())}") from e
    try:
        check_region_options(options)
    except ValueError as e:
        raise ConfigError(str(e)) from e
    return options


def main(argv=None) -> int:
    parser = ArgumentParser(prog="python -m drake_sim.tools.regions", description=__doc__)
    parser.add_argument(
        "--scene", type=input_file("scene file"), required=True, help="pick-and-place scene YAML"
    )
    parser.add_argument("--named", nargs="*", default=["ready"], help="named seed states")
    parser.add_argument("--no-pick-place", action="store_true", help="no pre-grasp/pre-place")
    parser.add_argument("--approach-height", type=positive_float, default=0.12, help="m")
    parser.add_argument(
        "--seeds", type=input_file("seeds file"), help="YAML list of 7-joint seeds, rad"
    )
    parser.add_argument("--options", type=input_file("options file"), help="RegionOptions YAML")
    parser.add_argument("--set", action="append", default=[], help="RegionOptions key=value")
    args = parser.parse_args(argv)
    options = _load_options(args)

    from planning import PlanningError, PlanningScene, RobotState
    from planning.search.iris_regions import load_or_build_regions

    scene = PlanningScene()
    state = RobotState(scene)
    try:
        scene.load_yaml(args.scene)
        seeds = [state.named(name) for name in args.named]
        if not args.no_pick_place:
            seeds += pick_place_seeds(scene, state, args.approach_height)
    except PlanningError as e:
        raise ConfigError(e.message) from e
    if args.seeds is not None:
        seeds += _read_seeds(args.seeds)
    if not seeds:
        raise ConfigError("no seeds: give --named, --seeds or a scene with an object")
    step, close = _progress()
    start = time.perf_counter()
    try:
        regions = load_or_build_regions(scene, seeds, options, progress=step)
    except ValueError as e:
        raise ConfigError(str(e)) from e
    except RuntimeError as e:
        print(f"failed: {e}", file=sys.stderr)
        return 1
    finally:
        close()
    how = "loaded from" if regions.loaded else "built and saved to"
    print(
        f"{len(regions.regions)} regions for {len(seeds)} seeds {how} {regions.path} "
        f"in {time.perf_counter() - start:.1f} s (build time {regions.build_time:.1f} s)"
    )
    return 0


def _read_seeds(path: Path) -> list[np.ndarray]:
    import yaml

    try:
        data = yaml.safe_load(path.read_text())
        seeds = np.asarray(data, dtype=float).reshape(-1, 7)
    except (OSError, yaml.YAMLError, ValueError, TypeError) as e:
        raise ConfigError(f"--seeds {path}: not a YAML list of 7-joint lists ({e})") from e
    return list(seeds)


if __name__ == "__main__":
    sys.exit(run(main))
