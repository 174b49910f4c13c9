"""Acceptance (slow): the shipped scenario (config/walle_scenario.yaml, unchanged) balances and
follows every shipped course with robots of other sizes and masses than config/walle.yaml's.
Headless, simulated time, seeded IMU noise."""

import json

import pytest

from drake_sim.robots.walle_params import write_walle_params
from drake_sim.runs.walle import RECIPE
from drake_sim.worlds.course import shipped_courses

robot = RECIPE.load().robot  # config/walle.yaml

# Known failure (strict, so a fix shows up as XPASS): the 1.25x robot's camera, 0.44 m up, sees
# past the oval's, the S-bend's and the loop's 0.5 m of floor in the turns; the detector takes
# the floor's level as the median grey of the whole image, the light background included, so
# the line's contrast drops under ``min_contrast`` ("no line: contrast 47 grey levels"), the
# follower searches, and the lap is not done in time (course fraction 0.08 to 0.62).
CAMERA_SEES_PAST_THE_FLOOR = pytest.mark.xfail(
    strict=True,
    reason="1.25x: the background beyond the floor raises the detector's floor level",
)
SCALES = [
    pytest.param(0.8, 1.0, id="lengths-x0.8"),
    pytest.param(1.25, 1.0, id="lengths-x1.25"),
    pytest.param(1.0, 0.7, id="masses-x0.7"),
    pytest.param(1.0, 1.5, id="masses-x1.5"),
]
"""(length, mass) factors of config/walle.yaml's dimensions and masses."""


@pytest.mark.slow
@pytest.mark.parametrize("path", shipped_courses(), ids=lambda p: p.stem)
@pytest.mark.parametrize("length, mass", SCALES)
def test_scaled_robots_balance_and_follow_every_shipped_course(tmp_path, length, mass, path):
    """The robot file is written to YAML and read back, as a user would: the whole course (a
    full lap on a loop), no fall, within 5 cm of the line at worst and 1.5 cm on average."""
    robot_file = tmp_path / "walle.yaml"
    write_walle_params(robot.scaled(length=length, mass=mass), robot_file)
    overrides = ["mode=both", f"course={json.dumps(str(path))}"]
    run = RECIPE.start(robot=robot_file, overrides=overrides)
    run.run(run.default_duration(viewer=False))
    report = run.report()
    print(
        f"x{length:g} lengths x{mass:g} masses on {path.stem}: end {report.end}, "
        f"fraction {report.course_fraction:.2f}, laps {report.laps}, "
        f"offset mean {report.mean_line_offset_m:.4f} m max {report.max_line_offset_m:.4f} m, "
        f"max pitch {report.max_abs_pitch_deg:.2f} deg"
    )
    assert not report.fell
    assert report.course_fraction == 1.0 and report.laps >= 1
    assert report.end == ("lap" if run.course.closed else "finish")
    assert report.max_line_offset_m <= 0.05
    assert report.mean_line_offset_m <= 0.015
