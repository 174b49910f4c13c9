"""Helpers of the pick-and-place tests."""

from planning.task.scene_generator import random_scene  # noqa: F401 (re-exported for the tests)


def run_task(config, mode: str, *, monitor=None):
    """Builds the station for ``config`` (a scenario) and runs its task; returns (report,
    interface)."""
    from diagrams.planning_station import make_planning_station
    from planning.task.pick_place import PickPlaceTask

    interface = make_planning_station(config, mode=mode)
    if monitor is not None:
        interface.add_monitor(monitor)
    return PickPlaceTask(interface, config.task).run(), interface
