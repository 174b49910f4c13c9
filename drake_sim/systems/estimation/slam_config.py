"""The scan-matching SLAM's parameters (``SlamConfig``) and their YAML file: the mapping and
navigation scenarios' ``slam`` section. The values were measured in the tests and benchmarks
named beside them; ``scan_matching_slam`` says what each does to a scan."""

import dataclasses as dc
from pathlib import Path

import numpy as np

from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError
from drake_sim.systems.estimation.loop_closure import LoopClosureConfig


@dc.dataclass
class SlamConfig:
    """Parameters of ``ScanMatchingSlam`` (values measured in ``tests/.../test_scan_matching_slam``
    and ``benchmarks/slam_benchmark.py``)."""

    resolution: float = 0.05  # m, cells of the map that ``map()`` returns and ``save()`` writes.
    levels: int = 3  # Pyramid levels from that map up; level k has cells of resolution * 2^k.
    # Finer levels below it, cells of resolution / 2^k (k = 1..fine_levels), matched last: a
    # scan's end points peak at occupied cells' centres, so matching is good to a fraction of
    # the finest cell; one finer level halves the drift of a long run (measured in the tests).
    fine_levels: int = 1
    map_size: float = 30.0  # m, side of the square maps, centred on the start (``map_square``).
    map_update_distance: float = 0.2  # m travelled since the last map update.
    map_update_angle_deg: float = 15.0  # Degrees turned since the last map update.
    initial_map_updates: int = 3  # The first scans always update the map.
    p_hit: float = 0.7  # Occupancy probability of a beam's end cell.
    p_miss: float = 0.4  # Occupancy probability of a cell a beam crossed.
    clamp: float = 4.0  # Log-odds bound.
    # m: returns this close to the sensor's range_max count as no return. Near the limit the
    # range noise decides which returns are kept (those short of it), so the walls seen there
    # were drawn short and pulled the pose after them (a maze: 2 cm in 0.6 s).
    range_margin: float = 0.1
    # m: when positive, a beam with no return clears the map this far only (Cartographer's
    # missing_data_ray_length); 0: to the range limit. A SICK's "no echo" may be glass as well
    # as open space, and clearing its 80 m is half the cost of a real log's map updates, but
    # at 5 m MIT CSAIL's loop no longer closed (2.3 m of error against 0.03 m): off.
    no_return_range: float = 0.0
    # Hits go this many cells beyond the beam's end along the surface's normal, in [0, 1)
    # (module docstring; 0: hector's end cell).
    hit_offset: float = 0.5
    # Gauss-Newton steps per level, finest first: fine_levels + levels numbers.
    iterations: list[int] = dc.field(default_factory=lambda: [4, 4, 4, 4])
    smoothing: float = 0.0  # Gaussian blur of each level's map for matching, cells.
    # When positive, match against a likelihood field of this width (cells) around the occupied
    # cells instead of the occupancy probabilities (see ``MatchMap.from_grid``); 0: hector's
    # probabilities.
    field: float = 1.0
    # Weight of the prior towards the odometry's prediction: m^-2, m^-2, rad^-2.
    prior_weight: list[float] = dc.field(default_factory=lambda: [50.0, 50.0, 50.0])
    max_correction: float = 0.3  # m: a match further from the prediction is rejected.
    max_correction_deg: float = 20.0  # Degrees, likewise.
    # A match whose end points score below this (mean map value on the level at resolution)
    # is rejected. 0.55 held in the simulated arenas but not on real logs: where the map ahead
    # is young and sparse (Intel, scan 548) real matches score 0.4 to 0.5, were refused, the
    # odometry's poses went into the map, and matching never recovered (8.9 m of error).
    min_score: float = 0.3
    min_points: int = 20  # Scans with fewer returns are not matched.
    # When the scan's normals spread (``scan_matcher.normal_spread``) in one direction less
    # than this fraction of the other, the position along it is the odometry's prediction (a
    # corridor). Measured: under 0.03 in a corridor, above 0.07 in rooms.
    degenerate_ratio: float = 0.05
    # ...unless the scan has at least this many depth discontinuities
    # (``scan_matcher.depth_edges``: a door's jamb, a pillar), which fix the position along it.
    # Real corridors have them: 729 of Intel's 791 scans (every third) whose normals all face
    # one way have 2 or more, and with them matched along the corridor Intel's error fell from
    # 0.021 m to 0.019 (ACES 0.039 to 0.038). A featureless simulated corridor has none.
    degenerate_edges: int = 2
    # After a match the gate rejects, the scan is searched for exhaustively within this far of
    # the prediction (m; 0: no search) and this many degrees (``correlative_search``) on the
    # map's occupied cells, and matched again from the best pose there if it scores at least
    # ``recovery_min_score`` (the table's mean at the scan's points). A log's odometry can be
    # off by more than the gate for a scan (Intel's bag, read in its stamps' order, paired some
    # scans with odometry 0.2 to 0.4 m old); the prediction then went into the map and
    # matching never recovered. A pose found is refused when another one the loop closures'
    # ``ambiguity_distance`` away scores above their ``max_ambiguity`` times its score: on
    # Intel with 1 mm of range noise (seed 4), two such guesses late in the log pulled the
    # trajectory apart (0.152 m of error; 0.021 with this test, 0.018 without the noise).
    recovery_window: float = 0.5
    recovery_window_deg: float = 20.0
    recovery_min_score: float = 0.6
    # A pose graph with loop closures over the matcher (``graph_slam.GraphSlam``); off by default.
    loop_closure: LoopClosureConfig = dc.field(default_factory=LoopClosureConfig)

    def check(self, where: str = "SlamConfig") -> None:
        """Raises ``ConfigError`` naming the first out-of-range key."""
        positive = ("resolution", "map_size", "clamp", "max_correction", "max_correction_deg")
        for key in positive:
            if not getattr(self, key) > 0:
                raise ConfigError(f"{where}: '{key}' must be positive, got {getattr(self, key)}")
        for key in (
            "map_update_distance",
            "map_update_angle_deg",
            "smoothing",
            "degenerate_ratio",
            "range_margin",
            "no_return_range",
            "recovery_window",
            "recovery_window_deg",
        ):
            if getattr(self, key) < 0:
                raise ConfigError(f"{where}: '{key}' must not be negative")
        if self.levels < 1 or self.resolution * 2 ** (self.levels - 1) > self.map_size:
            raise ConfigError(f"{where}: 'levels' must be at least 1 and fit in 'map_size'")
        if not 0.0 < self.recovery_min_score <= 1.0:
            raise ConfigError(f"{where}: 'recovery_min_score' must be in (0, 1]")
        if not 0.5 < self.p_hit < 1.0:
            raise ConfigError(f"{where}: 'p_hit' must be in (0.5, 1), got {self.p_hit}")
        if not 0.0 <= self.hit_offset < 1.0:
            raise ConfigError(f"{where}: 'hit_offset' must be in [0, 1), got {self.hit_offset}")
        if not 0.0 < self.p_miss < 0.5:
            raise ConfigError(f"{where}: 'p_miss' must be in (0, 0.5), got {self.p_miss}")
        if self.fine_levels < 0:
            raise ConfigError(f"{where}: 'fine_levels' must not be negative")
        count = self.fine_levels + self.levels
        if len(self.iterations) != count or min(self.iterations) < 0:
            raise ConfigError(
                f"{where}: 'iterations' needs {count} counts >= 0 (fine_levels + levels)"
            )
        if len(self.prior_weight) != 3 or min(self.prior_weight) < 0:
            raise ConfigError(f"{where}: 'prior_weight' needs 3 weights >= 0 (x, y, yaw)")
        if self.degenerate_edges < 0:
            raise ConfigError(f"{where}: 'degenerate_edges' must not be negative")
        if self.initial_map_updates < 1 or self.min_points < 1:
            raise ConfigError(f"{where}: 'initial_map_updates' and 'min_points' must be >= 1")
        self.loop_closure.check(f"{where}: loop_closure")


def load_slam_config(path: Path | str) -> SlamConfig:
    """Loads and checks a ``SlamConfig`` YAML file (missing keys keep their defaults)."""
    config = load_typed(SlamConfig, filename=path)
    config.check(str(path))
    return config


def map_square(low, high, initial_xy, map_size: float, margin: float = 1.0):
    """(centre (x, y), side m) of square maps that hold the box ``low``..``high`` (x, y m) and
    ``margin`` more: ``map_size`` centred on ``initial_xy`` when that holds it, else centred on
    the box, as large as it needs (at least ``map_size``)."""
    initial = np.asarray(initial_xy, dtype=float)
    low = np.minimum(np.asarray(low, dtype=float), initial) - margin
    high = np.maximum(np.asarray(high, dtype=float), initial) + margin
    if np.all(initial - map_size / 2 <= low) and np.all(initial + map_size / 2 >= high):
        return initial, float(map_size)
    # ``margin`` more of slack: the grids' corner snaps down to the coarsest cells' lattice.
    return (low + high) / 2, max(float(map_size), float(np.max(high - low)) + margin)
