"""Animations (dyncheck/pages/animation.py, engines/render.py): the frames are the engine's kinematics of the run,
the GIF is the same bytes when made again, both renderers give the same frames' times and size, and
`report --no-animations` makes none."""

import os
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from PIL import Image

import dyncheck
from dyncheck.case.folder import Case
from dyncheck.checks import drawings
from dyncheck.checks.runs import run_case
from dyncheck.common import style
from dyncheck.common.style import check_text
from dyncheck.pages import animation
from dyncheck.pages.report import write_reports
from dyncheck.results.values import save_results


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
    rows = drawings.at_times(run, frames.times)
    # no fastest frequency, no angle among its (prescribed) coordinates: a slow motion's frames
    assert 10 < len(frames.times) <= drawings.SLOW_FRAMES and np.all(np.diff(frames.times) >= drawings.MIN_INTERVAL - 1e-9)
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


def test_frames_follow_the_fastest_motion_shown():
    """At least FRAMES_PER_PERIOD frames a period of the fastest motion, the longest multiple of the output step
    that gives them; a slow motion at most SLOW_FRAMES, MIN_INTERVAL apart; never more than MAX_FRAMES."""
    run = pd.DataFrame({"x": 0.0}, index=np.arange(3001) * 1e-3)  # 3 s at 1 ms, as the spring pendulum's
    gap = lambda rows: run.index[rows[1]] - run.index[rows[0]]
    rows = drawings.frame_rows(run, 103.9)  # its spring's fastest frequency
    assert gap(rows) <= 2 * np.pi / (drawings.FRAMES_PER_PERIOD * 103.9) < gap(rows) + 1e-3
    assert len(rows) == 429 and run.index[rows[-1]] > 3.0 - gap(rows)  # the whole run
    slow = drawings.frame_rows(run, 0.0)
    assert len(slow) <= drawings.SLOW_FRAMES and gap(slow) >= drawings.MIN_INTERVAL
    assert np.array_equal(drawings.frame_rows(run, 1.0), slow)  # a slow motion needs no more
    assert len(drawings.frame_rows(run, 400.0)) == drawings.MAX_FRAMES  # the first 0.5 s only
    # Browsers show a GIF's 0 or 10 ms frames for 100 ms: a faster motion plays slowed down.
    times = run.index[rows].to_numpy()
    assert animation.delay(times) == animation.MIN_DELAY
    assert animation.pace(times, animation.delay(times)) == "2.9 times slower than real time"
    assert animation.pace(run.index[slow].to_numpy(), animation.delay(run.index[slow].to_numpy())) == "about real time"


def test_the_fastest_motion_shown_is_the_faster_of_the_frequency_and_a_turn():
    case = dyncheck.load_case("spring_pendulum")  # fastest frequency 104 rad/s; psi an angle, l a length
    still = pd.DataFrame({"psi_rate": [0.0, 1.0], "l_rate": [0.0, 500.0]})
    assert drawings.fastest_shown(case, {"exact": still}) == pytest.approx(103.92, abs=0.01)
    turning = pd.DataFrame({"psi_rate": [0.0, -150.0], "l_rate": [0.0, 0.0]})
    assert drawings.fastest_shown(case, {"exact": still, "program": turning}) == 150.0


def test_a_long_heading_is_wrapped_inside_the_frame(piston):
    """Every text of a frame inside it (write_gif refuses one that runs off, as style.save does a figure's): a
    heading wider than the panel goes on more lines."""
    spec = {**piston.spec, "title": "a piston on a turning arm, its extension and the arm's angle both prescribed, "
                                    "drawn in the inertial frame"}
    animator = animation.Animator(piston, Case(piston.folder, piston.overrides, spec), None)
    animator.show(len(animator.times) - 1)
    check_text(animator.fig, "frame")
    assert animator.title.count("\n") >= 1
    style.pyplot().close(animator.fig)


@pytest.mark.full
def test_every_case_animation_follows_its_fastest_motion(results, example_results):
    """Each case's frames, as its checks saved them, take a period of its fastest motion in FRAMES_PER_PERIOD or
    more (the output step allowing), or are a slow motion's."""
    for result in [*results.values(), *example_results.values()]:
        case, frames = case_of(result), result.drawings["animation"]["exact"]
        omega = drawings.fastest_shown(case, drawings.animated_runs(case, result.runs, result.program))
        gap, step = np.diff(frames.times[:2])[0], np.diff(result.runs["reference"].twin.index[:2])[0]
        if omega:
            assert gap <= max(2 * np.pi / (drawings.FRAMES_PER_PERIOD * omega), step) + 1e-9, case.name
        assert len(frames.times) <= drawings.MAX_FRAMES


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
from dyncheck.pages import animation
from dyncheck.common import style
from dyncheck.case.folder import Case
from dyncheck.results.values import load_result
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
