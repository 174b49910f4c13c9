"""The API documentation (pdoc, from the docstrings) builds without warnings."""

import subprocess
import sys

import pytest

pytest.importorskip("pdoc")

PACKAGES = ("drake_sim", "planning", "diagrams")


def test_api_docs_build_without_warnings(tmp_path):
    result = subprocess.run(
        [sys.executable, "-W", "error", "-m", "pdoc", *PACKAGES, "-o", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr
    assert "warn" not in result.stderr.lower(), result.stderr
    for package in PACKAGES:
        assert (tmp_path / f"{package}.html").is_file()
    assert (tmp_path / "drake_sim" / "systems" / "control" / "flip_controller.html").is_file()
