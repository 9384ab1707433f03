"""Animations (dyncheck/animation.py, engines/render.py): the frames are the engine's kinematics of the run,
the GIF is the same bytes when made again, both renderers give the same frames' times and size, and
`report --no-animations` makes none."""

import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

import dyncheck
from dyncheck import animation
from dyncheck.case import Case
from dyncheck.checks import run_case
from dyncheck.results import save_results
from dyncheck.report import write_reports


@pytest.fixture(scope="module")
def piston():
    """A case that runs in seconds (its motions prescribed), moving in 3-D."""
    return run_case(dyncheck.load_case("piston"), localise=False)


def case_of(result):
    return Case(result.folder, result.overrides, result.spec)


def test_frames_are_the_engines_kinematics(piston):
    """The mass's dot at each frame is MuJoCo's centre of mass of the body at the run's state then, and the
    traced path that the report saved with the run passes through it."""
    case, frames = case_of(piston), piston.drawings["animation"]["exact"]
    run = piston.runs["reference"].twin
    model = case.model("mujoco")
    rows = animation.at_times(run, frames.times)
    assert 10 < len(frames.times) <= animation.MAX_FRAMES and np.all(np.diff(frames.times) >= animation.MIN_INTERVAL - 1e-9)
    for i in (0, len(rows) // 2, len(rows) - 1):
        t, q = run.index[rows[i]], run[list(case.coords)].to_numpy()[rows[i]]
        centres, origins, _ = model.points(t, q)
        assert np.array_equal(frames.dots[i], centres)  # the one massive body is the traced one
        assert any(np.array_equal(end, origins[-1]) for end in frames.segments[i, :, 1])  # the arm reaches the mass
        assert np.allclose(frames.dots[i, 0], run[["mass_x", "mass_y", "mass_z"]].to_numpy()[rows[i]], atol=1e-15)
    assert not np.allclose(frames.dots[0], frames.dots[-1])  # it moves


def test_the_gif_is_the_same_bytes_again(piston, tmp_path):
    case = case_of(piston)
    count, interval = animation.write_gif(piston, case, tmp_path / "a.gif")
    animation.write_gif(piston, case, tmp_path / "b.gif")
    data = (tmp_path / "a.gif").read_bytes()
    assert data == (tmp_path / "b.gif").read_bytes()
    assert len(data) < 1_000_000
    with Image.open(tmp_path / "a.gif") as gif:
        assert gif.n_frames == count == len(piston.drawings["animation"]["exact"].times)
        assert gif.size == (animation.WIDTH, animation.HEIGHT) and gif.info["loop"] == 0
        assert gif.info["duration"] == interval


@pytest.mark.full
def test_no_animations_makes_none(piston, tmp_path):
    write_reports([piston], tmp_path / "without", animations=False)
    assert not list((tmp_path / "without").rglob("*.gif"))
    assert "Not made this time (`dyncheck report --no-animations`)." in (tmp_path / "without" / "piston.md").read_text()
    write_reports([piston], tmp_path / "with")
    assert [p.name for p in (tmp_path / "with").rglob("*.gif")] == ["piston_animation.gif"]
    page = (tmp_path / "with" / "piston.md").read_text()
    assert "![animation of piston](figures/piston_animation.gif)\n\n*Figure: " in page


RENDER_BOTH = """
import sys
from pathlib import Path
import numpy as np
from dyncheck import animation
from dyncheck.case import Case
from dyncheck.results import load_result
result = load_result(Path(sys.argv[1]))
case = Case(result.folder, result.overrides, result.spec)
gl = animation.painter(animation.WIDTH, animation.HEIGHT)
if gl is None:
    print("no context")
    sys.exit(0)
drawn = {}
for name, renderer in (("matplotlib", None), ("mujoco", gl)):
    animator = animation.Animator(result, case, renderer)
    images = [animator.frame(i) for i in (0, len(animator.times) - 1)]
    drawn[name] = (tuple(animator.times), images[0].size, images[0].tobytes() != images[1].tobytes())
    images[1].save(Path(sys.argv[2]) / f"{name}.png")
assert drawn["matplotlib"] == drawn["mujoco"], drawn
print("same")
"""


@pytest.mark.full
def test_both_renderers_draw_the_same_frames(piston, tmp_path):
    """MuJoCo's renderer (MUJOCO_GL=egl) and matplotlib: the same frame times and image size, both moving;
    skipped where no OpenGL context opens."""
    save_results([piston], tmp_path)
    done = subprocess.run([sys.executable, "-c", RENDER_BOTH, str(tmp_path / "piston"), str(tmp_path)],
                          capture_output=True, text=True, env={**os.environ, "MUJOCO_GL": "egl"})
    assert done.returncode == 0, done.stderr
    if done.stdout.strip() == "no context":
        pytest.skip("no OpenGL context for MuJoCo's renderer here (MUJOCO_GL=egl)")
    assert done.stdout.strip() == "same"
