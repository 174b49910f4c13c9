"""``--record-log`` (drake_sim.runs.ros_recording): the option opens a log, a complete run's
log goes to its name with the final map, an incomplete one beside it as ``.partial.mcap``."""

import numpy as np
import pytest

import drake_sim.runs.ros_recording as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.mcap_files import McapLogReader

MAP = OccupancyMap(np.zeros((3, 3), np.int8), 0.05)


def _topics(path):
    reader = McapLogReader(path)
    reader.open()
    try:
        return {c.topic: c.msgcount for c in reader.connections}
    finally:
        reader.close()


def test_no_option_no_log_and_a_bad_name_is_bad_input(tmp_path):
    assert mut.open_ros_log({}) is None
    assert mut.close_ros_log(None, complete=True, seconds=1.0) is None
    with pytest.raises(ConfigError, match="FILE.mcap"):
        mut.open_ros_log({"record_log": tmp_path / "run.bag"})


def test_a_complete_run_s_log_has_the_final_map(tmp_path, capsys):
    writer = mut.open_ros_log({"record_log": tmp_path / "run.mcap"})
    path = mut.close_ros_log(writer, complete=True, seconds=3.0, final_map=MAP)
    assert path == tmp_path / "run.mcap" and _topics(path) == {"/map": 1}
    assert f"ROS 2 log: {path} (1 messages)" in capsys.readouterr().out


def test_an_incomplete_run_s_log_is_partial_and_the_old_one_stays(tmp_path, capsys):
    (tmp_path / "run.mcap").write_bytes(b"a complete log")
    writer = mut.open_ros_log({"record_log": tmp_path / "run.mcap"})
    path = mut.close_ros_log(writer, complete=False, seconds=3.0)
    assert path == tmp_path / "run.partial.mcap" == mut.partial_path(tmp_path / "run.mcap")
    assert (tmp_path / "run.mcap").read_bytes() == b"a complete log"
    assert "run.mcap is kept as it was" in capsys.readouterr().out
