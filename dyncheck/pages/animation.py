"""Animations of a case's motion: a GIF on its page, made from the saved results.

What a frame shows is computed with the runs (`frames`, called by dyncheck.checks.runs where the engines are):
the scene's skeleton (engines.render.skeleton: lines from each body's origin to what hangs on it, a dot
per mass, a disk's rim for a rigid body) from MuJoCo's forward kinematics of the run's states at the
frame times.  The page's GIF (`section`) is drawn from those arrays by matplotlib, or by MuJoCo's own
renderer where the user asks for it (MUJOCO_GL=egl or osmesa) and an OpenGL context opens: the same
frame times and size either way.  The traced bodies' paths (the case's `scene.paths`) grow behind them.

A case's `[animation]` table chooses what is shown beside the motion: the book's program run beside (or
ghosted over) the exact motion, a force as an arrow, a quantity's graph growing with the frames.
"""

import math
import os
from dataclasses import dataclass

import numpy as np
from PIL import Image

from dyncheck.checks.drawings import FRAMES_PER_PERIOD, MAX_FRAMES, animated_runs, at_times, fastest_shown
from dyncheck.common.expressions import evaluate, namespace
from dyncheck.common.style import MIN_FONT, check_text, embed, pyplot, wrapped
from dyncheck.results import measured
from dyncheck.results.values import Frames, heading

MIN_DELAY = 20  # ms a frame is shown at least: browsers show a GIF's 0 or 10 ms frames for 100 ms
WIDTH = 400  # pixels of one 3-D panel; a frame is a panel wide per panel
HEIGHT = 360
DPI = 100
COLOURS = 64  # the GIF's palette: the figure's few colours and their antialiased edges
GL_BACKENDS = ("egl", "osmesa")  # MUJOCO_GL values under which MuJoCo's renderer draws
VIEW = dict(elev=22.0, azim=-55.0)  # matplotlib's 3-D camera, degrees


# -- drawing ---------------------------------------------------------------------------------------

def painter(width, height):
    """MuJoCo's renderer where MUJOCO_GL asks for one and a context opens, else None (matplotlib)."""
    if os.environ.get("MUJOCO_GL") not in GL_BACKENDS:
        return None
    try:
        from engines.render import MujocoPainter
        return MujocoPainter(width, height)
    except Exception:  # no engine here (report --from), or no OpenGL context: matplotlib draws
        return None


@dataclass(frozen=True)
class Panel:
    """A 3-D (or planar) view of one run's frames, with what is drawn over it."""
    title: str
    frames: Frames
    paths: np.ndarray  # (time, body, 3) of the traced bodies along the whole run
    path_times: np.ndarray
    ghost: Frames | None = None
    arrows: np.ndarray | None = None  # (frame, 2, 3): start and end


def panels(result, case):
    """The 3-D panels of a case's animation and the graph beside them (None for none)."""
    spec = case.spec.get("animation", {})
    shown = result.drawings["animation"]
    runs = {"exact": result.runs["reference"].twin}
    if "program" in shown:
        runs["program"] = result.program["listing"]
    traced = lambda run: np.stack([run[[f"{body}_{axis}" for axis in "xyz"]].to_numpy()
                                   for body in case.scene.paths], axis=1) if case.scene.paths else \
        np.zeros((len(run), 0, 3))
    exact_title = "exact: the corrected equations, tightly solved" if "program" in shown else "the motion"
    program_title = (f"the book's program: {result.program.get('integrator')}, dt = {result.program.get('dt', 0):.2g} s"
                     if "program" in shown else "")
    arrows = arrow(spec.get("arrow"), case, runs["exact"], shown["exact"]) if spec.get("arrow") else None
    exact = Panel(exact_title, shown["exact"], traced(runs["exact"]), runs["exact"].index.to_numpy(),
                  ghost=shown.get("program") if spec.get("program") == "ghost" else None, arrows=arrows)
    out = [exact]
    if spec.get("program") == "beside" and "program" in shown:
        out.insert(0, Panel(program_title, shown["program"], traced(runs["program"]), runs["program"].index.to_numpy()))
    return out, spec.get("graph")


def arrow(item, case, run, frames):
    """A force along `run` as arrows at the frames: from the point `at` along the force, the largest
    as long as half the scene's extent."""
    names = namespace(case, run)
    rows = at_times(run, frames.times).clip(max=len(names["t"]) - 1)  # the case's stop cuts the run
    force = np.stack([np.broadcast_to(evaluate(c, names), names["t"].shape)[rows] for c in item["force"]], axis=1)
    start = np.stack([np.broadcast_to(evaluate(c, names), names["t"].shape)[rows] for c in item["at"]], axis=1)
    extent = np.ptp(points(frames).reshape(-1, 3), axis=0).max()
    scale = 0.5 * extent / max(np.linalg.norm(force, axis=1).max(), 1e-300)
    return np.stack([start, start + scale * force], axis=1)


def points(frames):
    """Every point a run's frames draw: (frame, n, 3)."""
    return np.concatenate([frames.segments.reshape(len(frames.times), -1, 3), frames.dots,
                           frames.rims.reshape(len(frames.times), -1, 3)], axis=1)


def bounds(panel_list):
    """The view every panel shares: (low, high) corners, and the axes the motion uses (a planar motion's
    constant axis dropped)."""
    every = np.concatenate([np.concatenate([points(p.frames).reshape(-1, 3), p.paths.reshape(-1, 3),
                                            *([] if p.arrows is None else [p.arrows.reshape(-1, 3)])])
                            for p in panel_list])
    every = every[np.all(np.isfinite(every), axis=1)]
    low, high = every.min(axis=0), every.max(axis=0)
    used = [i for i in range(3) if high[i] - low[i] > 1e-9 * max(1.0, np.abs(every).max())]
    half = 0.55 * (high - low).max()
    centre = (low + high) / 2
    return centre - half, centre + half, used


class Animator:
    """The animation's figure, drawn once; `show(i)` moves its artists to frame i (faster than drawing
    every frame anew).  `gl`: MuJoCo's renderer draws the 3-D panels as images, or None: matplotlib."""

    def __init__(self, result, case, gl):
        self.panels, graph = panels(result, case)
        self.low, self.high, self.used = bounds(self.panels)
        self.gl = gl
        count = len(self.panels) + bool(graph)
        self.fig = pyplot().figure(figsize=(WIDTH * count / DPI, HEIGHT / DPI), dpi=DPI, layout="none")  # axes placed by add_axes
        self.title = wrapped(self.fig, heading(case.spec), MIN_FONT + 1)
        self.heading = self.fig.suptitle("", fontsize=MIN_FONT + 1)
        self.updates = []  # functions of the frame's index that move the artists
        self.moving = [self.heading]  # the artists they move; the rest is drawn once (`background`)
        self.background = None
        # Below the heading (its lines and the time's) and a panel's title, above the ticks and x label.
        line = 1.25 * (MIN_FONT + 1) / 72 * DPI / HEIGHT
        top = 0.98 - (self.title.count("\n") + 2) * line - 2.2 * line
        bottom = 0.14
        for k, panel in enumerate(self.panels):
            rect = (k / count + 0.07 / count, bottom, 0.86 / count, top - bottom)
            if gl is not None:
                ax = self.fig.add_axes(rect)
                ax.set_axis_off()
                picture = ax.imshow(np.zeros((HEIGHT, WIDTH, 3), dtype=np.uint8))
                self.moving.append(picture)
                self.updates.append(lambda i, panel=panel, picture=picture: picture.set_data(self.gl_image(panel, i)))
            else:
                ax = self.fig.add_axes(rect, projection=None if len(self.used) < 3 else "3d")
                self.updates.append(self.matplotlib_panel(ax, panel))
            ax.set_title(panel.title, fontsize=MIN_FONT)
        if graph:
            ax = self.fig.add_axes(((count - 1) / count + 0.14 / count, 0.16, 0.78 / count, top - 0.16))
            grow, line = graph_panel(ax, graph, namespace(case, result.runs["reference"].twin))
            self.moving.append(line)
            self.updates.append(lambda i: grow(self.times[i]))

    @property
    def times(self):
        return self.panels[-1].frames.times

    def show(self, i):
        for update in self.updates:
            update(i)
        self.heading.set_text(f"{self.title}\nt = {self.times[i]:.3f} s")

    def matplotlib_panel(self, ax, panel):
        """The panel's artists drawn at frame 0, and the function that moves them to frame i."""
        pick = lambda xyz: [np.asarray(xyz)[..., j] for j in self.used]
        skeletons = ([(panel.ghost, dict(color="tab:red", alpha=0.45))] if panel.ghost is not None else []) \
            + [(panel.frames, dict(color="0.25"))]
        moves = []
        for f, style in skeletons:
            for s in range(f.segments.shape[1]):
                line, = ax.plot(*pick(f.segments[0, s]), lw=2, **style)
                moves.append((line, lambda i, f=f, s=s: f.segments[i, s]))
            for r in range(f.rims.shape[1]):
                line, = ax.plot(*pick(f.rims[0, r]), lw=1.2, **({"color": "tab:green"} | style if "alpha" in style
                                                               else {**style, "color": "tab:green"}))
                moves.append((line, lambda i, f=f, r=r: f.rims[i, r]))
            for d, mass in enumerate(f.masses):
                size = 9 * (mass / f.masses.max()) ** (1 / 3) + 3
                line, = ax.plot(*pick(f.dots[0, d][None]), "o", ms=size, **style)
                moves.append((line, lambda i, f=f, d=d: f.dots[i, d][None]))
        for b in range(panel.paths.shape[1]):
            line, = ax.plot(*pick(panel.paths[:1, b]), color="tab:blue", lw=1.2)
            moves.append((line, lambda i, b=b: panel.paths[panel.path_times <= panel.frames.times[i] + 1e-9, b]))
        if panel.arrows is not None:
            line, = ax.plot(*pick(panel.arrows[0]), color="tab:purple", lw=2.5, marker="o", markevery=[1], ms=4)
            moves.append((line, lambda i: panel.arrows[i]))
        axes_names = "xyz"
        for j, setter in zip(self.used, (ax.set_xlim, ax.set_ylim, getattr(ax, "set_zlim", None))):
            setter(self.low[j], self.high[j])
        ax.set_xlabel(f"{axes_names[self.used[0]]} [m]", fontsize=MIN_FONT)
        ax.set_ylabel(f"{axes_names[self.used[1]]} [m]", fontsize=MIN_FONT)
        ax.tick_params(labelsize=MIN_FONT)
        if len(self.used) == 3:
            ax.set_zlabel("z [m]", fontsize=MIN_FONT)
            ax.view_init(**VIEW)
            ax.set_box_aspect((1, 1, 1))
            ax.locator_params(nbins=4)
            set_data = lambda line, xyz: line.set_data_3d(*pick(xyz))
        else:
            ax.set_aspect("equal")
            ax.grid(alpha=0.3)
            ax.locator_params(nbins=5)  # tick labels that do not run into each other
            set_data = lambda line, xyz: line.set_data(*pick(xyz))

        def move(i):
            for line, where in moves:
                set_data(line, where(i))
        self.moving += [line for line, _ in moves]
        return move

    def gl_image(self, panel, i):
        """MuJoCo's rendering of one panel at frame i, looking across a planar motion's plane."""
        centre, extent = (self.low + self.high) / 2, (self.high - self.low).max()
        if len(self.used) == 3:
            azimuth, elevation = VIEW["azim"] + 180.0, -VIEW["elev"]
        else:
            flat = ({0, 1, 2} - set(self.used)).pop()
            azimuth, elevation = {0: (0.0, 0.0), 1: (90.0, 0.0), 2: (90.0, -90.0)}[flat]
        f = panel.frames
        sizes = 0.02 * extent * (f.masses / f.masses.max()) ** (1 / 3) if len(f.masses) else []
        return self.gl.image((centre, 1.9 * extent, azimuth, elevation), f.segments[i], f.dots[i], sizes, f.rims[i],
                             arrows=[] if panel.arrows is None else [panel.arrows[i]])

    def frame(self, i):
        """Frame i as an RGB image: the moving artists drawn over the figure's background, which is drawn
        once (the axes, their ticks and labels: most of the drawing time)."""
        canvas = self.fig.canvas
        if self.background is None:
            for artist in self.moving:
                artist.set_animated(True)
            canvas.draw()
            self.background = canvas.copy_from_bbox(self.fig.bbox)
        self.show(i)
        canvas.restore_region(self.background)
        for artist in self.moving:
            self.fig.draw_artist(artist)
        return Image.fromarray(np.asarray(canvas.buffer_rgba())[..., :3].copy())


def graph_panel(ax, graph, names):
    """The graph beside the motion: the quantity up to the frame's time, and dashed its largest value over
    the run (for a friction demand: the least friction coefficient); returns the function of time that
    grows it."""
    t = names["t"]
    y = np.broadcast_to(evaluate(graph["y"], names), t.shape)
    line, = ax.plot(t[:1], y[:1], color="black", lw=1)
    finite = y[np.isfinite(y)]
    if len(finite):
        ax.axhline(finite.max(), color="0.4", ls="--", lw=0.8)
        ax.text(t[0], finite.max(), f" largest: {finite.max():.3g}", va="bottom", fontsize=MIN_FONT)
    ax.set_xlim(t[0], t[-1])
    if graph.get("ylim"):
        ax.set_ylim(*graph["ylim"])
    else:
        ax.set_ylim(*(lambda lo, hi: (lo - 0.05 * (hi - lo), hi + 0.1 * (hi - lo)))(finite.min(), finite.max()))
    ax.set_xlabel("t [s]", fontsize=MIN_FONT)
    ax.set_ylabel(graph["ylabel"], fontsize=MIN_FONT)
    ax.set_title(graph["title"], fontsize=MIN_FONT)
    ax.tick_params(labelsize=MIN_FONT)
    ax.grid(alpha=0.3)
    return (lambda t_now: line.set_data(t[t <= t_now + 1e-9], y[t <= t_now + 1e-9])), line


def write_gif(result, case, path, gl=None):
    """The case's animation as a GIF at `path`: every frame drawn, one palette for all, looping, each
    frame shown for the time between frames, at least MIN_DELAY (`delay`).  `gl`: MuJoCo's renderer, or
    None.  Returns the number of frames and the time each is shown (ms).  A text that would run off the
    frame's edge is refused (ValueError), as dyncheck.common.style.save refuses it in a figure."""
    animator = Animator(result, case, gl)
    animator.show(len(animator.times) - 1)  # the heading's widest time
    check_text(animator.fig, path)
    images = [animator.frame(i) for i in range(len(animator.times))]
    pyplot().close(animator.fig)
    # One palette from the first, middle and last frames side by side: every colour drawn, every path grown.
    sample = [images[0], images[len(images) // 2], images[-1]]
    montage = Image.new("RGB", (sample[0].width * 3, sample[0].height))
    for k, image in enumerate(sample):
        montage.paste(image, (k * image.width, 0))
    palette = montage.quantize(COLOURS, method=Image.Quantize.MEDIANCUT)
    frames_p = [image.quantize(palette=palette, dither=Image.Dither.NONE) for image in images]
    interval = delay(animator.times)
    # optimize: each frame stores only the pixels that changed (the rest transparent), a fifth of the bytes
    frames_p[0].save(path, save_all=True, append_images=frames_p[1:], duration=interval, loop=0, optimize=True)
    return len(images), interval


def delay(times):
    """How long each frame is shown, ms: the time between frames in the GIF's hundredths of a second, at
    least MIN_DELAY (a motion sampled faster plays slowed down)."""
    return max(MIN_DELAY, 10 * round(100 * (times[1] - times[0]))) if len(times) > 1 else 100


def pace(times, shown):
    """The GIF's speed in words, from the time between frames and the time each is shown (ms)."""
    if len(times) < 2:
        return "a still"
    slower = shown / (1000 * (times[1] - times[0]))
    return "about real time" if abs(slower - 1) < 0.1 else f"{slower:.2g} times slower than real time"


def caption(result, case, count, interval):
    """What the animation shows, and what to see in it."""
    spec = case.spec.get("animation", {})
    exact = result.runs["reference"].twin
    shown = result.drawings["animation"]
    times = shown["exact"].times
    gap = times[1] - times[0] if len(times) > 1 else 0.0
    span = (f"over {exact.index[-1]:g} s" if times[-1] + gap > exact.index[-1] - 1e-9
            else f"over the first {times[-1]:.3g} s of the {exact.index[-1]:g} s run (at most {MAX_FRAMES} frames)")
    omega = fastest_shown(case, animated_runs(case, result.runs, result.program))
    rate = (f", at least {FRAMES_PER_PERIOD} a period of the fastest motion shown ({omega:.3g} rad/s)"
            if gap and omega and FRAMES_PER_PERIOD * gap <= 2 * math.pi / omega + 1e-9 else "")
    parts = [f"{heading(case.spec)}: the motion from {'the initial state' if case.one_derivation else 'the book’s initial conditions'},"
             f" {count} frames {span}{rate}, each shown {interval} ms ({pace(times, interval)}), drawn from the"
             " engine's forward kinematics of each run: grey lines from each body's origin to what hangs on it, a"
             " dot per mass (its area grows with the mass)"
             + (", the green ring the rim of the uniform disk with the body's largest moment of inertia" if
                any(f.rims.shape[1] for f in shown.values()) else "")
             + (", in blue the path of " + ", ".join(case.scene.paths) if case.scene.paths else "") + "."]
    if "program" in shown:
        where = "ghosted in red over the exact motion" if spec["program"] == "ghost" else "on the left, the exact motion on the right"
        parts.append(f"The book's program ({result.program['integrator']}, dt = {result.program['dt']:.2g} s) {where}.")
    if spec.get("arrow"):
        parts.append(f"The purple arrow: {spec['arrow']['about']}.")
    if spec.get("graph"):
        parts.append(f"Right: {spec['graph']['title']}, growing with the frames; dashed, its largest value.")
    if spec.get("caption"):
        parts.append(" ".join(measured.fill(result, case.prose(spec["caption"], "animation.caption")).split()))
    return " ".join(parts)


def section(result, case, tmp, make):
    """The case page's "Animation" section and the files it wrote.  `make`: False under `dyncheck report
    --no-animations`."""
    lines = ["## Animation", ""]
    shown = result.drawings.get("animation")
    if not make:
        return lines + ["Not made this time (`dyncheck report --no-animations`).", ""], []
    if not shown:
        return lines + ["None: the reference's run failed or these results hold no frames (made before"
                        " animations were; run the checks again).", ""], []
    gif = f"figures/{case.name}_animation.gif"
    gl = painter(WIDTH, HEIGHT)
    try:
        count, interval = write_gif(result, case, tmp / gif, gl)
    finally:
        if gl is not None:
            gl.close()
    text = caption(result, case, count, interval)
    return lines + embed(gif, f"animation of {case.name}", text), [gif]
