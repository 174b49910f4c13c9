"""drake_sim.systems.estimation.particle_filter: AMCL on the shipped arenas' ground-truth maps,
synthetic scans (exact 2D ray casting, 1 cm noise) and drifting odometry along driven routes.
(Its parts alone: test_motion_model.py, test_likelihood_field.py, test_pose_histogram.py,
test_map_refinement.py.)

The helpers here (``drive``, ``drifting_odometry``, ``localise``) are also used by
``test_amcl.py`` and ``benchmarks/amcl_benchmark.py``.
"""

import dataclasses as dc
import math

import numpy as np
import pytest
from scipy import ndimage

import drake_sim.systems.estimation.particle_filter as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.planar import compose, relative_pose, wrap_angle
from drake_sim.base.resources import config_dir
from drake_sim.systems.estimation.amcl_config import AmclConfig, load_amcl_config
from drake_sim.worlds.arena import arena_footprints, arena_grid, load_arena, shipped_arenas
from drake_sim.worlds.footprints import cast_rays
from drake_sim.worlds.route import default_route_file, load_route

RATE = 5.0  # Hz, scans (the LDS-01's)
SPEED, TURN_RATE = 0.2, 0.8  # m/s, rad/s
SCAN_HEIGHT = 0.17  # m, the TurtleBot3's lidar plane
SENSOR = (-0.064, 0.0, 0.0)  # X_base_sensor of the TurtleBot3's LDS-01
ANGLES = -math.pi + 2 * math.pi * np.arange(360) / 360
RANGE_MIN, RANGE_MAX, RANGE_SIGMA = 0.12, 3.5, 0.01  # m
SHIPPED = config_dir() / "amcl.yaml"


def drive(start, waypoints, duration: float) -> np.ndarray:
    """Poses (k, 3) one scan apart over ``duration`` s along the route: turn on the spot at
    TURN_RATE towards each waypoint, then drive straight to it at SPEED."""
    poses, dt = [np.asarray(start, dtype=float)], 1.0 / RATE
    steps = int(round(duration * RATE))
    for target in waypoints:
        while len(poses) <= steps:
            x, y, yaw = poses[-1]
            turn = float(wrap_angle(math.atan2(target[1] - y, target[0] - x) - yaw))
            distance = math.hypot(target[0] - x, target[1] - y)
            if distance < 1e-9:
                break
            if abs(turn) > 1e-9:
                poses.append(
                    np.array([x, y, yaw + math.copysign(min(abs(turn), TURN_RATE * dt), turn)])
                )
                continue
            s = min(distance, SPEED * dt)
            poses.append(np.array([x + s * math.cos(yaw), y + s * math.sin(yaw), yaw]))
    return np.array(poses[: steps + 1])


YAW_DRIFT = math.radians(0.5)  # rad per m


def drifting_odometry(truth: np.ndarray, rng, scale=0.01, yaw_per_m=YAW_DRIFT):
    """Odometry along ``truth``: ``scale`` too long, ``yaw_per_m`` rad of yaw drift per m and
    a little noise (the mapping scenario's wheel calibration errors are 1 % and 0.5 %)."""
    odometry = [truth[0]]
    for before, after in zip(truth[:-1], truth[1:], strict=True):
        step = relative_pose(before, after)
        length = math.hypot(step[0], step[1])
        step[:2] *= 1.0 + scale
        step[2] += yaw_per_m * length + rng.normal(0.0, 0.001)
        odometry.append(compose(odometry[-1], step))
    return np.array(odometry)


def scan_at(footprints, pose, rng) -> np.ndarray:
    """360 ranges (m, ``inf`` for no return) of the lidar on the base at ``pose``."""
    x, y, yaw = compose(pose, SENSOR)
    ranges = cast_rays(footprints, np.array([[x, y]]), ANGLES + yaw, RANGE_MAX)[0]
    return ranges + rng.normal(0.0, RANGE_SIGMA, ranges.shape)


def world(name: str):
    """(arena, footprints the lidar sees, ground-truth 0.05 m map) of a shipped arena."""
    path = config_dir() / "arenas" / f"{name}.yaml"
    arena = load_arena(path)
    footprints = arena_footprints(arena, height=SCAN_HEIGHT)
    return arena, footprints, arena_grid(arena, 0.05, height=SCAN_HEIGHT), path


def localise(name, config, seed, duration, *, offset=None, global_localization=False):
    """Drives the arena's default route with a filter; returns (filter, rows) with one row
    ``[t, position error m, yaw error deg, particles]`` per filter update."""
    arena, footprints, grid, path = world(name)
    truth = drive(arena.start_pose(), load_route(default_route_file(path)).waypoints, duration)
    rng = np.random.default_rng(seed)
    odometry = drifting_odometry(truth, rng)
    dut = mut.ParticleFilter(grid, config, seed)
    if global_localization:
        dut.global_localization()
    else:
        dut.set_pose(truth[0] + offset, np.diag([0.5**2, 0.5**2, math.radians(30) ** 2]))
    rows = []
    for k, (pose, odom) in enumerate(zip(truth, odometry, strict=True)):
        ranges = scan_at(footprints, pose, rng)
        if dut.update(
            odom, ranges, ANGLES, range_max=RANGE_MAX, range_min=RANGE_MIN, X_base_sensor=SENSOR
        ):
            estimate, _ = dut.estimate()
            yaw_error = math.degrees(abs(float(wrap_angle(estimate[2] - pose[2]))))
            rows.append(
                [k / RATE, math.dist(estimate[:2], pose[:2]), yaw_error, len(dut.particles)]
            )
    return dut, np.array(rows)


def off_guess(seed: int) -> np.ndarray:
    """An initial guess error 0.5 m away in a seeded direction and 30 degrees off."""
    rng = np.random.default_rng(1000 + seed)
    direction = rng.uniform(-math.pi, math.pi)
    return np.array(
        [
            0.5 * math.cos(direction),
            0.5 * math.sin(direction),
            math.radians(30) * rng.choice([-1, 1]),
        ]
    )


@pytest.fixture(scope="module")
def shipped():
    return load_amcl_config(SHIPPED)


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("arena", [p.stem for p in shipped_arenas()])
def test_tracking_from_a_rough_guess_converges_within_10_s(shipped, arena, seed):
    _, rows = localise(arena, shipped, seed, 16.0, offset=off_guess(seed))
    assert rows[0, 1] > 0.25 or rows[0, 2] > 15  # it did start far off
    after = rows[rows[:, 0] >= 10.0]
    assert len(after) >= 12  # updates kept coming while driving (every 0.08 m)
    assert after[:, 1].max() < 0.05, after[:, 1].max()
    assert after[:, 2].max() < 3.0, after[:, 2].max()
    assert rows[-1, 3] < shipped.max_particles / 2  # KLD shrank the set once converged


def test_global_localization_converges_in_the_room(shipped):
    dut, rows = localise("room", shipped, 3, 70.0, global_localization=True)
    assert rows[0, 1] > 0.5 and rows[0, 3] == shipped.max_particles
    after = rows[rows[:, 0] >= 60.0]
    assert len(after) >= 10
    assert after[:, 1].max() < 0.05 and after[:, 2].max() < 3.0
    _, covariance = dut.estimate()
    assert np.sqrt(np.diag(covariance))[:2].max() < 0.1


def test_same_seed_same_particles_other_seed_others(shipped):
    runs = [localise("room", shipped, seed, 3.0, offset=off_guess(1))[0] for seed in (5, 5, 6)]
    np.testing.assert_array_equal(runs[0].particles, runs[1].particles)
    np.testing.assert_array_equal(runs[0].weights, runs[1].weights)
    assert runs[0].particles.shape != runs[2].particles.shape or not np.array_equal(
        runs[0].particles, runs[2].particles
    )


def empty_map() -> OccupancyMap:
    """A 10 m x 10 m free map with no obstacle (its corner at (-5, -5))."""
    return OccupancyMap(np.zeros((200, 200), dtype=np.int8), 0.05, (-5.0, -5.0, 0.0))


def test_updates_only_after_moving_or_turning_enough():
    config = AmclConfig(update_min_d=0.2, update_min_a=0.5, max_particles=200)
    dut = mut.ParticleFilter(empty_map(), config, 0)
    scan = np.full(8, np.inf), np.linspace(-3, 3, 8)
    update = lambda odom: dut.update(odom, *scan, range_max=3.5)  # noqa: E731
    assert update([0.0, 0.0, 0.0])  # the first scan always updates
    assert not update([0.1, 0.1, 0.2])
    assert update([0.15, 0.15, 0.0])  # 0.21 m from the last update
    assert not update([0.15, 0.15, 0.45])
    assert not update([0.15, 0.15, -0.4])
    assert update([0.15, 0.15, -0.6])  # 0.6 rad from the last update
    assert dut.updates == 3
    dut.set_pose([0.0, 0.0, 0.0], np.eye(3) * 0.01)
    assert update([0.15, 0.15, -0.6])  # a restart always updates


def test_motion_moves_the_particles_by_the_odometry_since_the_last_update():
    """(The models themselves: test_motion_model.py.)"""
    alpha = dict(odom_alpha1=0.0, odom_alpha2=0.0, odom_alpha3=0.04, odom_alpha4=0.0)
    config = AmclConfig(max_particles=2000, update_min_d=0.0, **alpha)
    dut = mut.ParticleFilter(empty_map(), config, 3)
    dut.set_pose([1.0, 0.0, math.pi / 2], np.zeros((3, 3)), odom_pose=[0.0, 0.0, 0.0])
    assert dut.update([1.0, 0.0, 0.0], np.full(4, np.inf), np.zeros(4), range_max=3.5)
    np.testing.assert_allclose(dut.particles[:, 1].mean(), 1.0, atol=0.02)  # facing +y
    np.testing.assert_allclose(dut.particles[:, 0], 1.0, atol=1e-12)


def test_sensor_model_prefers_the_true_pose_and_skips_beams_without_return():
    arena, footprints, grid, _ = world("room")
    config = AmclConfig(max_particles=3, min_particles=3, laser_max_beams=90)
    dut = mut.ParticleFilter(grid, config, 0)
    truth = np.array([-2.2, -1.8, 0.0])
    dut.particles = np.array([truth, truth + [0.1, 0.0, 0.0], truth + [0.0, 0.0, 0.1]])
    dut.weights = np.full(3, 1 / 3)
    ranges = scan_at(footprints, truth, np.random.default_rng(0))
    dut.update(
        truth, ranges, ANGLES, range_max=RANGE_MAX, range_min=RANGE_MIN, X_base_sensor=SENSOR
    )
    # ROS's 1 + sum(pz^3) is a deliberately weak likelihood: 10 % more per scan here.
    assert dut.weights[0] > 1.1 * dut.weights[1] and dut.weights[0] > 1.1 * dut.weights[2]
    np.testing.assert_allclose(dut.weights.sum(), 1.0)
    # A scan with no returns (inf, at range_max or below range_min) carries no information.
    before = dut.weights.copy()
    useless = np.concatenate([np.full(120, np.inf), np.full(120, RANGE_MAX), np.full(120, 0.05)])
    dut.set_pose(truth, np.zeros((3, 3)))
    dut.particles, dut.weights = dut.particles[:3], before
    dut.update(truth, useless, ANGLES, range_max=RANGE_MAX, range_min=RANGE_MIN)
    np.testing.assert_array_equal(dut.weights, before)


def test_likelihood_is_ros_sum_of_cubed_beam_likelihoods_on_the_distance_field():
    _, footprints, grid, _ = world("warehouse")
    config = AmclConfig(min_particles=2, max_particles=2, laser_max_beams=40)
    dut = mut.ParticleFilter(grid, config, 0)
    poses = np.array([[-5.2, -3.8, 0.3], [4.0, 3.5, -2.0]])
    dut.particles, dut.weights = poses.copy(), np.array([0.5, 0.5])
    ranges = scan_at(footprints, [-5.1, -3.7, 0.2], np.random.default_rng(1))
    ranges[::7] = np.inf
    dut.update(
        [0, 0, 0], ranges, ANGLES, range_max=RANGE_MAX, range_min=RANGE_MIN, X_base_sensor=SENSOR
    )
    # The same by hand: the 40 beams, those with a return, their end points' distances.
    beams = np.round(np.linspace(0, 359, 40)).astype(int)
    beams = beams[np.isfinite(ranges[beams])]
    distance = ndimage.distance_transform_edt(grid.cells < 65) * grid.resolution
    expected = []
    for pose in poses:
        sensor = compose(pose, SENSOR)
        angle = sensor[2] + ANGLES[beams]
        ends = sensor[:2] + ranges[beams, None] * np.stack([np.cos(angle), np.sin(angle)], -1)
        rows, cols = grid.cell_of(ends)
        inside = grid.inside(rows, cols)
        d = np.full(len(ends), 2.0)
        d[inside] = np.minimum(distance[rows[inside], cols[inside]], 2.0)
        pz = 0.95 * np.exp(-(d**2) / (2 * 0.2**2)) + 0.05 / RANGE_MAX
        expected.append(1.0 + np.sum(pz**3))
    np.testing.assert_allclose(dut.weights, np.array(expected) / sum(expected), rtol=1e-9)
    assert dut.weights[0] > 3 * dut.weights[1]


def test_global_localization_spreads_particles_over_free_cells_only():
    arena, _, grid, _ = world("maze")
    dut = mut.ParticleFilter(grid, AmclConfig(min_particles=100, max_particles=4000), 1)
    dut.global_localization()
    assert len(dut.particles) == 4000
    assert np.all(grid.value_at(dut.particles[:, :2]) == 0)
    lo, hi = dut.particles[:, :2].min(0), dut.particles[:, :2].max(0)
    assert lo[0] < -3.3 and lo[1] < -2.8 and hi[0] > 3.3 and hi[1] > 2.8  # all over the maze
    assert np.std(dut.particles[:, 2]) > 1.5  # and every heading


def test_recovery_injects_random_particles_when_the_robot_is_kidnapped(shipped):
    arena, footprints, grid, _ = world("room")
    truth, kidnapped = np.array([-2.2, -1.8, 0.0]), np.array([1.8, 1.8, 2.0])
    spreads = {}
    for alpha_slow, alpha_fast in ((0.0, 0.0), (0.001, 0.1)):
        config = dc.replace(shipped, recovery_alpha_slow=alpha_slow, recovery_alpha_fast=alpha_fast)
        dut = mut.ParticleFilter(grid, config, 2)
        dut.set_pose(truth, np.diag([0.01, 0.01, 0.01]))
        rng = np.random.default_rng(2)
        for k in range(30):  # turning on the spot: an update at every scan
            odom = [0.0, 0.0, 0.12 * k]
            pose = (truth if k < 15 else kidnapped) + [0.0, 0.0, 0.12 * k]
            dut.update(
                odom,
                scan_at(footprints, pose, rng),
                ANGLES,
                range_max=RANGE_MAX,
                range_min=RANGE_MIN,
                X_base_sensor=SENSOR,
            )
        spreads[alpha_fast] = np.linalg.norm(dut.particles[:, :2] - truth[:2], axis=1).max()
    assert spreads[0.0] < 1.0  # without recovery the cloud stays where it was
    assert spreads[0.1] > 2.0  # with it, random particles appear all over the room


def test_bad_initial_poses_are_config_errors():
    dut = mut.ParticleFilter(empty_map(), AmclConfig(min_particles=10, max_particles=10), 0)
    with pytest.raises(ConfigError, match="initial pose"):
        dut.set_pose([0.0, math.nan, 0.0], np.eye(3))
    with pytest.raises(ConfigError, match="positive semi-definite"):
        dut.set_pose([0.0, 0.0, 0.0], -np.eye(3))
    with pytest.raises(ConfigError, match="symmetric"):
        dut.set_pose([0.0, 0.0, 0.0], np.triu(np.ones((3, 3))))


REFINED = AmclConfig(
    min_particles=500, max_particles=500, laser_max_beams=90, scan_match_refinement=True
)


def one_update(name, config, truth, offset, *, ranges=None):
    """A filter whose particles all sit at ``truth + offset`` takes one scan made at ``truth``
    (or ``ranges``); returns the filter."""
    _, footprints, grid, _ = world(name)
    dut = mut.ParticleFilter(grid, config, 0)
    dut.set_pose(np.asarray(truth) + offset, np.diag([1e-8, 1e-8, 1e-10]))
    if ranges is None:
        ranges = scan_at(footprints, truth, np.random.default_rng(0))
    assert dut.update(
        truth, ranges, ANGLES, range_max=RANGE_MAX, range_min=RANGE_MIN, X_base_sensor=SENSOR
    )
    return dut


@pytest.mark.parametrize("name, truth", [("maze", [0.3, 0.2, 0.4]), ("room", [-2.2, -1.8, 0.0])])
def test_scan_match_refinement_corrects_a_biased_estimate(name, truth):
    offset = np.array([0.04, -0.03, math.radians(1.5)])
    plain = one_update(name, dc.replace(REFINED, scan_match_refinement=False), truth, offset)
    estimate, _ = plain.estimate()
    assert math.dist(estimate[:2], truth[:2]) > 0.045  # the filter alone keeps the bias
    dut = one_update(name, dc.replace(REFINED, refinement_shift_particles=False), truth, offset)
    estimate, covariance = dut.estimate()
    assert dut.refinements == [1, 0]
    assert math.dist(estimate[:2], truth[:2]) < 0.015
    assert abs(float(wrap_angle(estimate[2] - truth[2]))) < math.radians(0.5)
    assert dut.last_match.scores[0] > REFINED.refinement_min_score
    # Only the estimate moved: the particles (and the covariance) are the filter's.
    np.testing.assert_allclose(dut.particles, plain.particles)
    np.testing.assert_allclose(covariance, plain.estimate()[1])


def test_scan_match_refinement_can_shift_the_particles_with_the_estimate():
    truth, offset = np.array([0.3, 0.2, 0.4]), np.array([0.04, -0.03, math.radians(1.5)])
    plain = one_update("maze", dc.replace(REFINED, scan_match_refinement=False), truth, offset)
    dut = one_update("maze", REFINED, truth, offset)
    estimate, covariance = dut.estimate()
    assert dut.refinements == [1, 0] and REFINED.refinement_shift_particles
    np.testing.assert_allclose(dut.particles.mean(axis=0), estimate, atol=1e-3)
    # A rigid move: the spread (and the covariance) is the filter's.
    np.testing.assert_allclose(covariance, plain.estimate()[1], rtol=1e-6, atol=1e-12)


def test_scan_match_refinement_rejects_bad_matches():
    truth = np.array([0.3, 0.2, 0.4])
    offset = np.array([0.04, -0.03, math.radians(1.5)])
    # A correction beyond the gate: the filter's estimate stands.
    gated = dc.replace(REFINED, refinement_max_correction=0.02)
    dut = one_update("maze", gated, truth, offset)
    assert dut.refinements == [0, 1]
    np.testing.assert_allclose(dut.estimate()[0], truth + offset, atol=1e-3)
    # A scan of somewhere else: no good match near the estimate.
    _, footprints, _, _ = world("maze")
    elsewhere = scan_at(footprints, truth + [0.0, 0.0, 2.0], np.random.default_rng(0))
    dut = one_update("maze", REFINED, truth, offset, ranges=elsewhere)
    assert dut.refinements == [0, 1]
    np.testing.assert_allclose(dut.estimate()[0], truth + offset, atol=1e-3)
    # Too few returns to match.
    few = np.full(360, np.inf)
    few[:10] = 1.0
    dut = one_update("maze", REFINED, truth, offset, ranges=few)
    assert dut.refinements == [0, 1]


def test_a_scan_too_blind_to_match_carries_the_last_match_by_the_odometry():
    truth, offset = np.array([-2.2, -1.8, 0.0]), np.array([0.04, -0.03, math.radians(1.5)])
    blind = np.full(len(ANGLES), np.inf)  # open floor: nothing within the lidar's reach
    moved = compose(truth, (0.3, 0.02, 0.1))  # the odometry's next pose
    runs = {}
    for carry in (False, True):  # the last one goes on below
        dut = one_update(
            "room", dc.replace(REFINED, refinement_blind_odometry=carry), truth, offset
        )
        fix, _ = dut.estimate()
        assert dut.update(
            moved, blind, ANGLES, range_max=RANGE_MAX, range_min=RANGE_MIN, X_base_sensor=SENSOR
        )
        assert dut.refinements == [1, 1]
        runs[carry] = (dut.estimate()[0], dut.particles.copy())
    carried = compose(fix, relative_pose(truth, moved))
    np.testing.assert_allclose(runs[True][0], carried, atol=1e-12)
    assert math.dist(runs[False][0][:2], carried[:2]) > 1e-4  # the cloud's mean: motion noise
    np.testing.assert_allclose(runs[True][1], runs[False][1])  # the particles: the filter's
    # A few returns (too few to match, enough for the filter's own model): the filter's mean.
    few = scan_at(world("room")[1], moved, np.random.default_rng(2))
    few[np.arange(len(few)) % 60 != 0] = np.inf
    assert 0 < np.isfinite(few).sum() < REFINED.refinement_min_points
    dut = one_update("room", REFINED, truth, offset)
    dut.update(moved, few, ANGLES, range_max=RANGE_MAX, range_min=RANGE_MIN, X_base_sensor=SENSOR)
    assert dut.refinements == [1, 1] and math.dist(dut.estimate()[0][:2], carried[:2]) > 1e-4
    # The next scan that sees the room is matched again, from the carried pose.
    then = compose(moved, (0.3, 0.0, 0.0))
    scan = scan_at(world("room")[1], then, np.random.default_rng(1))
    assert dut.update(
        then, scan, ANGLES, range_max=RANGE_MAX, range_min=RANGE_MIN, X_base_sensor=SENSOR
    )
    assert dut.refinements == [2, 1]
    assert math.dist(dut.estimate()[0][:2], then[:2]) < 0.02
