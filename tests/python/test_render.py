"""Rendering from Python: sim.render() draws what `springy frames` writes, pixel for pixel, and
springy.frames / springy.render_video are the command line's commands."""
import numpy as np
import pytest
from PIL import Image

import springy
from conftest import scene

SPHERE = scene("single_sphere")


def png(path):
    return np.asarray(Image.open(path).convert("RGB"))


def test_a_rendered_array_equals_the_frames_png(tmp_path, springy_cli):
    # 1.8 s: the ball squashed on the ground, its shadow under it.
    springy_cli("frames", SPHERE, "--times", "1.8", "--width", 320, "--height", 180, "-o", tmp_path / "cli")
    still = png(tmp_path / "cli" / "single_sphere_t001.80.png")
    sim = springy.load(SPHERE)
    sim.run(until=1.8)
    image = sim.render(320, 180)
    assert image.shape == (180, 320, 3) and image.dtype == np.uint8
    assert np.array_equal(image, still)
    # Not a blank frame: sky, ground and ball differ.
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 500
    # A second draw at the same instant is the same; a later one is not.
    assert np.array_equal(sim.render(320, 180), image)
    sim.run(until=2.5)
    assert not np.array_equal(sim.render(320, 180), image)


def test_frames_writes_the_command_lines_stills(tmp_path, springy_cli):
    springy_cli("frames", SPHERE, "--times", "0,1.8", "--width", 160, "--height", 90, "--sheet",
                "-o", tmp_path / "cli")
    springy.frames(SPHERE, tmp_path / "py", times=[0, 1.8], width=160, height=90, sheet=True)
    for name in ("single_sphere_t000.00.png", "single_sphere_t001.80.png", "single_sphere_sheet.png"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name


def test_render_video_writes_the_command_lines_video(tmp_path, springy_cli):
    args = dict(duration=0.5, width=160, height=96)
    springy_cli("render", SPHERE, "--duration", 0.5, "--width", 160, "--height", 96, "-o", tmp_path / "cli.mp4")
    springy.render_video(SPHERE, tmp_path / "py.mp4", **args)
    assert (tmp_path / "py.mp4").read_bytes() == (tmp_path / "cli.mp4").read_bytes()
    assert (tmp_path / "py.mp4").stat().st_size > 1000


def test_a_failed_command_raises_with_its_message(tmp_path):
    with pytest.raises(springy.Error, match=r"springy frames failed \(exit status 1\).*--times: '20.0' is not within"):
        springy.frames(SPHERE, tmp_path, times=[20])
    with pytest.raises(springy.Error, match="--width 17: must be even"):
        springy.render_video(SPHERE, tmp_path / "a.mp4", width=17)
    assert not (tmp_path / "a.mp4").exists()
