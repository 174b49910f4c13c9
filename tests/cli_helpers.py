"""Helpers for the command-line tests: edited robot files and the bad-input contract."""

import yaml

from drake_sim.robots.ddrive import default_robot_file


def edited_robot_file(tmp_path, edit):
    """Writes ``config/ddrive.yaml`` after ``edit(data)`` to ``tmp_path`` and returns its path."""
    data = yaml.safe_load(default_robot_file().read_text())
    edit(data)
    path = tmp_path / "robot.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def assert_bad_input(result, needle):
    """A finished ``subprocess.run``: exit code 2, one stderr line naming ``needle``."""
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert needle in lines[0]
    assert "Traceback" not in result.stderr
