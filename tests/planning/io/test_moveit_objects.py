"""planning.io.moveit_objects: what cannot be represented is a warning naming the file and the
object (remembered as skipped), or with ``strict`` an error."""

import logging

import pytest

from planning.io import moveit_objects as mut


def test_issues_warn_once_per_line_and_remember_skipped_objects(caplog):
    issues = mut.Issues("scene.yaml")
    with caplog.at_level(logging.WARNING):
        issues.drop("world.collision_objects[0]", "a mesh nobody can read", "bowl")
        issues.drop("7", "no final '.'")
        issues.drop("world.collision_objects[1]", "again", "bowl")
    assert issues.warnings[0] == "scene.yaml: world.collision_objects[0]: a mesh nobody can read"
    assert issues.warnings[1] == "scene.yaml:7: no final '.'"
    assert issues.skipped == ["bowl"]
    assert len(caplog.records) == 3


def test_strict_issues_raise_naming_the_file():
    issues = mut.Issues("scene.yaml", strict=True)
    with pytest.raises(ValueError, match=r"^scene.yaml: objects\[2\]: a cone .*strict"):
        issues.drop("objects[2]", "a cone", "tip")
    assert issues.warnings == [] and issues.skipped == []
