"""One figure style for every page: a colour per integration scheme, a line style per source, the
plotting backend (files only, no display), and how every figure is saved and shown on a page.

A figure is drawn for print: at most `TEXT_WIDTH` wide (an A4 page's text width), every font at least
`MIN_FONT` points, saved as a PNG at `DPI` (the page) with a vector PDF twin beside it (print), both
byte-for-byte the same when drawn again from the same data. On a page every figure has a caption
under it (`embed`)."""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after choosing the backend)

# A source's curves over time: coinciding curves stay visible (the tight reference wide and pale).
SOURCE_STYLE = {
    "tight reference": dict(color="black", lw=2.6, alpha=0.35),
    "book": dict(color="tab:red", lw=1.0, ls="--"),
    "pinocchio": dict(color="tab:blue", lw=1.0, ls=":"),
    "mujoco": dict(color="tab:green", lw=1.0, ls="-."),
    "reference": dict(color="tab:orange", lw=1.0, ls=(0, (1, 3))),
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


TEXT_WIDTH = 6.3  # inches: A4 (210 mm) less two 25 mm margins, 160 mm
MIN_FONT = 8.0  # points, at TEXT_WIDTH: the smallest size a printed page keeps legible
DPI = 200  # the PNG's resolution; 1260 pixels across at TEXT_WIDTH


def save(fig, path):
    """Write `fig` to `path` (a .png) and its vector twin `path` with .pdf, then close it. Neither file
    carries a date, so a figure drawn again from the same data is the same bytes."""
    path = Path(path)
    fig.savefig(path, dpi=DPI, metadata={"Software": None})
    fig.savefig(path.with_suffix(".pdf"), metadata={"CreationDate": None, "Creator": None, "Producer": None})
    plt.close(fig)


def embed(path, alt, caption):
    """A figure on a page: the PNG (`path` relative to the page), and under it its caption, which says
    what the figure shows and what to see in it, with a link to the vector twin for print."""
    path = Path(path)
    return [f"![{alt}]({path.as_posix()})", "",
            f"*Figure: {caption.strip()}* ([vector PDF]({path.with_suffix('.pdf').as_posix()}))", ""]


def method_style(label):
    """Colour and marker of the method a label starts with ("RK4 dt = ..."), {} for none."""
    method = max((m for m in METHOD_COLOUR if label == m or label.startswith(m + " ")), key=len, default=None)
    return {} if method is None else dict(color=METHOD_COLOUR[method], marker=METHOD_MARKER[method])


__all__ = ["plt", "TEXT_WIDTH", "MIN_FONT", "DPI", "save", "embed", "SOURCE_STYLE", "SWEEP_STYLE", "METHOD_COLOUR", "METHOD_MARKER", "method_style"]
