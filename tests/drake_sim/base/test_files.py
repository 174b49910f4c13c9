"""Atomic writes: a target is either left whole or replaced whole, whatever stops the write."""

import os
import signal
import stat

import pytest

from drake_sim.base import files as mut
from drake_sim.base.errors import ConfigError


def _leftovers(folder):
    return [p.name for p in folder.iterdir() if p.name.endswith(".tmp")]


def test_write_atomic_writes_text_and_bytes_and_makes_folders(tmp_path):
    target = tmp_path / "a" / "b" / "report.json"
    assert mut.write_atomic(target, "{}\n") == target
    assert target.read_text() == "{}\n"
    mut.write_atomic(target, b"\x00\x01")
    assert target.read_bytes() == b"\x00\x01"
    assert _leftovers(target.parent) == []


def test_write_atomic_keeps_the_permission_bits_of_the_file_it_replaces(tmp_path):
    target = tmp_path / "map.yaml"
    target.write_text("old")
    os.chmod(target, 0o640)
    mut.write_atomic(target, "new")
    assert stat.S_IMODE(target.stat().st_mode) == 0o640
    assert target.read_text() == "new"


def test_an_interrupted_write_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    target = tmp_path / "map.pgm"
    target.write_bytes(b"complete map")

    def interrupted(fd):
        raise KeyboardInterrupt  # Ctrl-C while the new bytes are being flushed

    monkeypatch.setattr(mut.os, "fsync", interrupted)
    with pytest.raises(KeyboardInterrupt):
        mut.write_atomic(target, b"half a ma")
    assert target.read_bytes() == b"complete map"
    assert _leftovers(tmp_path) == []


def test_a_file_that_cannot_be_written_is_one_config_error_naming_it(tmp_path):
    target = tmp_path / "taken"
    target.mkdir()  # a folder where the file should go: the rename fails
    with pytest.raises(ConfigError, match="report cannot be written: .*taken"):
        mut.write_atomic(target, "x", "report")
    assert target.is_dir()
    assert _leftovers(tmp_path) == []


def test_write_atomic_many_replaces_no_target_when_one_cannot_be_staged(tmp_path):
    pgm, yml = tmp_path / "room.pgm", tmp_path / "room.yaml"
    pgm.write_bytes(b"old image")
    yml.write_text("old yaml")
    blocked = tmp_path / "file"
    blocked.write_text("a file, not a folder")
    with pytest.raises(ConfigError, match="map cannot be written"):
        mut.write_atomic_many([(pgm, b"new"), (yml, "new"), (blocked / "x.yaml", "x")], "map")
    assert pgm.read_bytes() == b"old image"
    assert yml.read_text() == "old yaml"
    assert _leftovers(tmp_path) == []


def test_write_atomic_many_writes_every_file(tmp_path):
    paths = mut.write_atomic_many([(tmp_path / "m.pgm", b"P5"), (tmp_path / "m.yaml", "image")])
    assert [p.name for p in paths] == ["m.pgm", "m.yaml"]
    assert (tmp_path / "m.pgm").read_bytes() == b"P5"
    assert (tmp_path / "m.yaml").read_text() == "image"


def test_a_signal_during_the_renames_waits_for_the_last_one():
    delivered = []
    previous = signal.signal(signal.SIGINT, lambda *_: delivered.append("SIGINT"))
    try:
        with mut.signals_held():
            os.kill(os.getpid(), signal.SIGINT)
            assert delivered == []  # held while the files are renamed
        assert delivered == ["SIGINT"]  # delivered at the block's end
    finally:
        signal.signal(signal.SIGINT, previous)
