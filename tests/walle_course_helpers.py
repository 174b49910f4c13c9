"""Shared set-up for the Wall-E course tests: the shipped robot and scenario, and the report's
contract keys (DESIGN.md, Wall-E course)."""

from drake_sim.robots.walle import default_robot_file
from drake_sim.robots.walle_params import load_walle_params
from drake_sim.runs.walle import RECIPE as WALLE

REPORT_KEYS = frozenset(
    [
        "fell",
        "time_upright_s",
        "max_abs_pitch_deg",
        "course_fraction",
        "laps",
        "lap_time_s",
        "mean_line_offset_m",
        "max_line_offset_m",
        "sim_time_s",
        "wall_time_s",
        "real_time_factor",
    ]
)
"""The keys every report has (more are allowed)."""


def walle_robot_and_scenario():
    """Returns config/walle.yaml's robot and config/walle_scenario.yaml's scenario."""
    return load_walle_params(default_robot_file()), WALLE.scenario.read(None)
