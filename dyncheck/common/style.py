"""One figure style for every page: a colour per integration scheme, a line style per source, the
plotting backend (files only, no display), and how every figure is saved and shown on a page.

A figure is drawn for print: at most `TEXT_WIDTH` wide (an A4 page's text width), every font at least
`MIN_FONT` points, saved as a PNG at `DPI` (the page) with a vector PDF twin beside it (print), both
byte-for-byte the same when drawn again from the same data. On a page every figure has a caption
under it (`embed`).

matplotlib is imported with the first figure (`pyplot`), not with this module: the checks and the
studies' computations import this module but draw nothing, and `dyncheck run` never loads matplotlib
(a quarter of a second of its start-up)."""

import functools
import textwrap
from pathlib import Path

import numpy as np
from PIL import Image

TEXT_WIDTH = 6.3  # inches: A4 (210 mm) less two 25 mm margins, 160 mm
TEXT_HEIGHT = 9.0  # inches: A4's text height (247 mm) less room for the caption under the figure
MIN_FONT = 8.0  # points, at TEXT_WIDTH: the smallest size a printed page keeps legible
DPI = 200  # the PNG's resolution; 1260 pixels across at TEXT_WIDTH

# Defaults that comply: a figure drawn without font sizes of its own reads at A4 width.
RC_PARAMS = {
    "font.size": 9, "axes.titlesize": 9, "axes.labelsize": 9, "figure.titlesize": 9.5,
    "xtick.labelsize": 8, "ytick.labelsize": 8, "legend.fontsize": 8, "legend.title_fontsize": 8,
    "figure.figsize": (TEXT_WIDTH, 3.6), "figure.constrained_layout.use": True, "savefig.dpi": DPI,
    "axes.grid": True, "grid.alpha": 0.3, "lines.markersize": 4, "pdf.compression": 9,
}


@functools.cache
def pyplot():
    """matplotlib.pyplot on the Agg backend (files only, no display) with RC_PARAMS: every figure is made
    through it (or `panels`), so that matplotlib is imported with the first figure and only then."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # after choosing the backend
    plt.rcParams.update(RC_PARAMS)
    return plt


# A source's curves over time, told apart in grey as well as in colour: a line style and a marker per
# source (markers spaced along the line, each source's shifted so that coinciding curves show all of
# theirs), and the tight reference wide and pale under the others.
SOURCE_STYLE = {
    "tight reference": dict(color="black", lw=2.6, alpha=0.35, ls="-", marker="o", mfc="none", markevery=(0.0, 0.1)),
    "book": dict(color="tab:red", lw=1.0, ls="--", marker="x", markevery=(0.02, 0.1)),
    "pinocchio": dict(color="tab:blue", lw=1.0, ls=":", marker="s", mfc="none", markevery=(0.04, 0.1)),
    "mujoco": dict(color="tab:green", lw=1.0, ls="-.", marker="^", mfc="none", markevery=(0.06, 0.1)),
    "reference": dict(color="tab:orange", lw=1.0, ls=(0, (5, 1, 1, 1, 1, 1)), marker="D", mfc="none",
                      ms=3.5, markevery=(0.08, 0.1)),
}
# A source's points in a sweep (work-precision): marker and line.
SWEEP_STYLE = {"reference": dict(marker="o", ls="-"), "derivation": dict(marker="o", ls="-"),  # a researcher's
               "pinocchio": dict(marker="s", ls="--"), "mujoco": dict(marker="^", ls=":")}
# The integration scheme: MuJoCo's Euler is the semi-implicit Euler and its RK4 the classical RK4, so
# they share a colour and differ by marker.
METHOD_COLOUR = {"explicit Euler": "tab:red", "semi-implicit Euler": "tab:orange", "mujoco:Euler": "tab:orange",
                 "mujoco:implicitfast": "tab:pink", "RK4": "tab:brown", "mujoco:RK4": "tab:brown",
                 "RK45": "tab:blue", "DOP853": "tab:purple", "Radau": "tab:green", "LSODA": "tab:olive"}
METHOD_MARKER = {"explicit Euler": "o", "semi-implicit Euler": "s", "mujoco:Euler": "x", "mujoco:implicitfast": "+",
                 "RK4": "^", "mujoco:RK4": "1", "RK45": "v", "DOP853": "D", "Radau": "P", "LSODA": "X"}


def save(fig, path):
    """Write `fig` to `path` (a .png) and its vector twin `path` with .pdf, then close it. Neither file
    carries a date, so a figure drawn again from the same data is the same bytes. A figure that would
    not print (wider than TEXT_WIDTH, taller than TEXT_HEIGHT, a text under MIN_FONT or cut off at the
    edge) is refused with a ValueError naming the file and what breaks the rule."""
    path = Path(path)
    try:
        check_size(fig, path)
        fig.savefig(path, dpi=DPI, metadata={"Software": None})  # lays the figure out
        fig.set_layout_engine("none")  # the check and the twin keep that layout: laid out once, the same in all
        try:
            check_text(fig, path)
        except ValueError:
            path.unlink()
            raise
        fig.savefig(path.with_suffix(".pdf"), metadata={"CreationDate": None, "Creator": None, "Producer": None})
        with Image.open(path) as image:  # a palette of 256 colours, undithered: a third of the bytes, same look
            paletted = image.convert("RGB").quantize(256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
        paletted.save(path, optimize=True)
    finally:
        pyplot().close(fig)


def check_size(fig, path):
    """ValueError unless `fig` fits the page's text width and height."""
    width, height = fig.get_size_inches()
    if width > TEXT_WIDTH + 1e-9:
        raise ValueError(f"{path}: the figure is {width:g} in wide, more than the page's text width {TEXT_WIDTH:g} in")
    if height > TEXT_HEIGHT + 1e-9:
        raise ValueError(f"{path}: the figure is {height:g} in tall, more than the page's {TEXT_HEIGHT:g} in")


def check_text(fig, path):
    """ValueError unless every text of `fig`, as last drawn, is at least MIN_FONT and inside the figure."""
    from matplotlib.text import Text  # matplotlib is loaded: `fig` is a figure (see pyplot)
    fig.draw_without_rendering()  # at the figure's own resolution, which the extents below are in
    renderer = fig.canvas.get_renderer()
    canvas = fig.bbox.padded(1.0)  # a pixel of slack for rounding
    # Tick labels outside the view are not drawn: only their size counts (the list keeps them, so ids hold).
    ticks = [label for ax in fig.axes for axis in ax._axis_map.values()
             for tick in axis.get_major_ticks() + axis.get_minor_ticks() for label in (tick.label1, tick.label2)]
    tick_ids = {id(label) for label in ticks}
    for text in fig.findobj(Text):
        if not text.get_visible() or not text.get_text().strip():
            continue
        if text.get_fontsize() < MIN_FONT - 1e-9:
            raise ValueError(f"{path}: the text {text.get_text()!r} is {text.get_fontsize():g} pt, under the "
                             f"{MIN_FONT:g} pt a printed page keeps legible")
        box = text.get_window_extent(renderer)
        if id(text) not in tick_ids and not (canvas.contains(box.x0, box.y0) and canvas.contains(box.x1, box.y1)):
            raise ValueError(f"{path}: the text {text.get_text()!r} runs off the figure's edge")


def title(name, what):
    """A figure's title: the example it belongs to (its heading, "1.8.3 Spring-mass pendulum ..."), then
    what the figure shows, on further lines when both would not fit the page's width.  A name longer than a line (a
    researcher's docstring's first sentence) is shortened to one, at a word: the page above gives it whole."""
    name = textwrap.shorten(name, 79, placeholder=" ...")  # and its colon: one line
    return f"{name}: {what}" if len(name) + len(what) < 80 else textwrap.fill(f"{name}:", 80) + "\n" + textwrap.fill(what, 80)


def wrapped(fig, text, fontsize):
    """`text` on as few lines as keep each within the width of `fig` at `fontsize`, as drawn: a title that
    would otherwise run off the figure's edges (fig.suptitle centres it, so its ends go first)."""
    renderer = fig.canvas.get_renderer()
    probe = fig.text(0, 0, text, fontsize=fontsize)
    try:
        for width in range(len(text), 0, -1):
            probe.set_text(textwrap.fill(text, width))
            if probe.get_window_extent(renderer).width <= 0.96 * fig.bbox.width:
                return probe.get_text()
        return probe.get_text()
    finally:
        probe.remove()


def panels(rows=1, cols=1, height=3.6, **options):
    """A figure of rows x cols axes at the page's text width, `height` inches tall (pyplot().subplots's
    options); the axes always as a 2-D array."""
    return pyplot().subplots(rows, cols, figsize=(TEXT_WIDTH, height), squeeze=False, **options)


def leave_out(axes, used, xlabel=None):
    """`axes` (a 2-D array from `panels`) with its panels after the first `used`, row by row, removed: a panel
    switched off kept its labels, which the layout placed off the figure.  With `xlabel`, the lowest panel left
    in each column gets it and its tick labels (a shared x axis shows them on the last row only)."""
    for ax in axes.flat[used:]:
        ax.remove()
    if xlabel is not None:
        rows, cols = axes.shape
        for lowest in (axes.flat[i] for i in range(min(used, rows * cols) - 1, -1, -1)[:cols]):
            lowest.xaxis.set_tick_params(labelbottom=True)
            lowest.set_xlabel(xlabel)


def legend_below(fig, handles=None, labels=None, ncol=3, **options):
    """The figure's legend under its axes, where it covers no curve."""
    if handles is None:
        handles, labels = unique_handles(fig)
    if handles:
        fig.legend(handles, labels, loc="outside lower center", ncol=min(ncol, len(handles)), frameon=False, **options)


def unique_handles(fig):
    """([handle], [label]) of every labelled artist of the figure's axes, each label once, in order."""
    found = {}
    for ax in fig.axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            found.setdefault(label, handle)
    return list(found.values()), list(found.keys())


def thin(frame, most=1500):
    """Every k-th row of `frame` (or array), at most about `most` rows, the last always kept: a dense
    series drawn at print resolution looks the same and keeps the vector twin small."""
    every = max(1, int(np.ceil(len(frame) / most)))
    if every == 1:
        return frame
    rows = np.r_[np.arange(0, len(frame) - 1, every), len(frame) - 1]
    return frame.iloc[rows] if hasattr(frame, "iloc") else np.asarray(frame)[rows]


SERIES_POINTS = 1000  # a run's output grid has thousands of points; a sweep's points, dozens


def log_range(values, decades_below=1):
    """(low, high) of a log axis for positive `values`: from a decade below the data's floor (zeros
    and non-finite values left out) to a bit above their top; (1e-16, 1) for no positive value.  The
    floor of a series along a run (SERIES_POINTS or more) is its 1st percentile: the run's exact start
    and rare cancellations would otherwise stretch the axis over decades no curve lives in; draw such
    values with numpy.maximum(values, low) so that those below lie on the axis's bottom edge."""
    values = np.concatenate([np.ravel(np.asarray(v, dtype=float)) for v in values]) if len(values) else np.array([])
    positive = values[np.isfinite(values) & (values > 0)]
    if not len(positive):
        return 1e-16, 1.0
    low = np.percentile(positive, 1) if len(positive) >= SERIES_POINTS else positive.min()
    high = positive.max()
    return 10 ** (np.floor(np.log10(low)) - decades_below), 10 ** (np.ceil(np.log10(high)) + 0.3)


def embed(path, alt, caption):
    """A figure on a page: the image (`path` relative to the page), and under it its caption, which says
    what the figure shows and what to see in it, with a link to the vector twin for print (a PNG's; an
    animation, a GIF, has none)."""
    path = Path(path)
    twin = ("an animation: no vector twin" if path.suffix == ".gif" else
            f"[vector PDF]({path.with_suffix('.pdf').as_posix()})")
    return [f"![{alt}]({path.as_posix()})", "", f"*Figure: {caption.strip()}* ({twin})", ""]


def along(source, points):
    """SOURCE_STYLE[source] for a curve of `points` points: its markers every tenth of the points (a noisy
    curve's length would crowd markers spaced by distance), each source's shifted as in SOURCE_STYLE."""
    start, every = SOURCE_STYLE[source]["markevery"]
    return {**SOURCE_STYLE[source], "markevery": (int(start * points), max(1, int(every * points)))}


def method_style(label):
    """Colour and marker of the method a label starts with ("RK4 dt = ..."), {} for none."""
    method = max((m for m in METHOD_COLOUR if label == m or label.startswith(m + " ")), key=len, default=None)
    return {} if method is None else dict(color=METHOD_COLOUR[method], marker=METHOD_MARKER[method])


__all__ = ["pyplot", "TEXT_WIDTH", "TEXT_HEIGHT", "MIN_FONT", "DPI", "save", "check_size", "check_text", "embed", "title", "wrapped", "panels",
           "leave_out", "legend_below", "unique_handles", "thin", "log_range", "SOURCE_STYLE", "along", "SWEEP_STYLE", "METHOD_COLOUR", "METHOD_MARKER", "method_style"]
