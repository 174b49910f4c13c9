"""``python -m drake_sim.tools.replay_frames``: frame times, the GIF, the camera and the CLI."""

import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image, ImageSequence

import drake_sim.tools.replay_frames as mut
from drake_sim import flip
from tests.browser_helpers import require_chromium, robot_pixels
from tests.cli_helpers import assert_bad_input


def _run(*args, env=None):
    return subprocess.run(
        [sys.executable, "-m", "drake_sim.tools.replay_frames", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )


def test_frame_times():
    assert mut.frame_times(4.0, 5) == pytest.approx([0.0, 1.0, 2.0, 3.0, 4.0])
    assert mut.frame_times(4.0, 3, start=1.0, end=3.0) == pytest.approx([1.0, 2.0, 3.0])
    assert mut.frame_times(4.0, 2, end=9.0) == pytest.approx([0.0, 4.0])  # Clipped.
    assert mut.frame_times(0.0, 3) == pytest.approx([0.0, 0.0, 0.0])  # No recording.
    assert mut.frame_times(4.0, 1, start=2.0) == pytest.approx([2.0])


def test_set_camera_script_uses_meshcats_y_up_frame():
    script = mut.set_camera_script(np.array([1.0, 2.0, 3.0]), [4, 5, 6])
    assert "'position', [1.0, 3.0, -2.0]" in script
    assert "set_camera_target([4.0, 6.0, -5.0])" in script


def test_save_gif_keeps_frames_colours_and_rate(tmp_path):
    pictures = []
    for i in range(6):
        picture = Image.new("RGB", (64, 40), (120, 120, 130))
        picture.paste((217, 115, 26), (i * 8, 10, i * 8 + 12, 22))  # An orange block moves.
        pictures.append(picture)
    out = tmp_path / "sub" / "out.gif"
    mut.save_gif(pictures, out, fps=5.0)
    gif = Image.open(out)
    assert gif.info["duration"] == 200
    assert gif.info["loop"] == 0
    frames = [f.convert("RGB") for f in ImageSequence.Iterator(gif)]
    assert len(frames) == 6
    for frame, picture in zip(frames, pictures, strict=True):
        error = np.abs(np.asarray(frame, int) - np.asarray(picture, int)).max()
        assert error <= 8
    with pytest.raises(ValueError):
        mut.save_gif([], out)


def test_cli_bad_input(tmp_path):
    assert_bad_input(_run(tmp_path / "missing.html", tmp_path / "out.gif"), "replay not found")
    replay = tmp_path / "replay.html"
    replay.write_text("<html></html>")
    assert_bad_input(_run(replay, tmp_path / "out.gif", "--size", "640"), "--size")
    assert_bad_input(_run(replay, tmp_path / "out.gif", "--frames", "0"), "--frames")
    assert_bad_input(_run(replay, tmp_path / "out.gif", "--camera", "1,2"), "--camera")
    env = {**os.environ, "DRAKE_SIM_CHROMIUM": ""}
    assert_bad_input(_run(replay, tmp_path / "out.gif", env=env), "no Chromium found")
    assert not (tmp_path / "out.gif").exists()


@pytest.mark.browser
def test_cli_makes_a_gif_of_a_flip_replay(tmp_path):
    require_chromium()
    bare, html, gif = tmp_path / "bare.yaml", tmp_path / "replay.html", tmp_path / "flip.gif"
    bare.write_text("scene: {world: ''}\n")
    args = ["--headless", "--duration", "1.5", "--config", str(bare), "--record", str(html)]
    assert flip.main(args) == 0
    result = _run(html, gif, "--frames", "4", "--size", "320x200", "--fps", "4")
    assert result.returncode == 0, result.stderr
    assert "4 frames" in result.stdout
    frames = [f.convert("RGB") for f in ImageSequence.Iterator(Image.open(gif))]
    assert len(frames) == 4
    assert frames[0].size == (320, 200)
    assert all(robot_pixels(f) > 30 for f in frames)
