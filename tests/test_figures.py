"""Every figure prints: rendered from this session's runs of the book's cases and the examples, each PNG has
its vector PDF twin and fits the page's text width, and every figure on every page has its caption
(dyncheck.common.style.embed).  dyncheck.common.style.save refuses what would not print."""

import re

import pytest

from dyncheck.common import style


@pytest.fixture(scope="module")
def pages(rendered):
    """Both report trees, rendered from this session's runs (conftest.rendered)."""
    return rendered / "reports"


def test_every_figure_has_a_vector_twin_and_fits_the_page(pages):
    from PIL import Image
    figures = sorted(pages.rglob("figures/*.png"))
    assert figures
    missing = [str(png) for png in figures if not png.with_suffix(".pdf").is_file()]
    assert not missing, missing
    wide = [(png.name, Image.open(png).size[0]) for png in figures if Image.open(png).size[0] > style.DPI * style.TEXT_WIDTH]
    assert not wide, wide


def test_every_figure_on_every_page_has_a_caption(pages):
    uncaptioned = []
    for page in sorted(pages.rglob("*.md")):
        lines = page.read_text().splitlines()
        for i, line in enumerate(lines):
            if re.match(r"!\[[^\]]*\]\([^)]*\)", line.strip()):
                following = next((later for later in lines[i + 1:] if later.strip()), "")
                if not following.startswith("*Figure: "):
                    uncaptioned.append(f"{page.name}: {line.strip()}")
    assert not uncaptioned, uncaptioned


def test_save_refuses_a_figure_that_would_not_print(tmp_path):
    fig, axes = style.panels(1, 1, 3.0)
    axes[0, 0].set_ylabel("too small to read", fontsize=6)
    with pytest.raises(ValueError, match="'too small to read' is 6 pt"):
        style.save(fig, tmp_path / "small.png")
    fig = style.pyplot().figure(figsize=(9.0, 3.0))
    with pytest.raises(ValueError, match="9 in wide"):
        style.save(fig, tmp_path / "wide.png")
    assert not list(tmp_path.iterdir())


def test_a_figure_drawn_twice_is_the_same_bytes(tmp_path):
    for name in ("a", "b"):
        fig, axes = style.panels(1, 1, 3.0)
        for source in style.SOURCE_STYLE:
            axes[0, 0].plot(range(50), [len(source) * x for x in range(50)], label=source, **style.along(source, 50))
        style.legend_below(fig)
        style.save(fig, tmp_path / f"{name}.png")
    for suffix in (".png", ".pdf"):
        assert (tmp_path / f"a{suffix}").read_bytes() == (tmp_path / f"b{suffix}").read_bytes()


def test_quantities_are_named_in_the_pages_words():
    """As the prose writes them (psi'', l''), typeset: a symbol in mathtext, primes for a rate or an
    acceleration, a vector's component after it; words stay words."""
    from dyncheck.pages.figures import quantity_label
    assert quantity_label("theta1_acc") == r"$\theta_{1}''$"
    assert quantity_label("omega3_dot_x") == r"$\omega_{3}'$ x"
    assert quantity_label("a_D_x") == "$a_{D}$ x"
    assert quantity_label("Rx") == "$R_{x}$"
    assert quantity_label("psi_rate (dependent)") == r"$\psi'$ (dependent)"
    assert quantity_label("precession_acc") == "precession''"
    assert quantity_label("drive_power") == "drive power"


def test_the_pointwise_panels_name_no_code(monkeypatch):
    """Each panel's title is the quantity in the page's words (it was the code's name, omega3_dot_x), and the
    dashed tolerance is in the legend."""
    import dyncheck
    from dyncheck.pages import figures
    from dyncheck.case.folder import Case
    from dyncheck.checks.runs import run_case
    result = run_case(dyncheck.load_case("piston"), localise=False)  # seconds: its motions prescribed
    drawn = {}
    monkeypatch.setattr(figures, "save", lambda fig, path: drawn.update(fig=fig))
    figures.figure_pointwise(result, Case(result.folder, result.overrides, result.spec), "x.png", words={})
    titles = [ax.get_title() for ax in drawn["fig"].axes if ax.get_title()]
    assert len(titles) == len(result.sample["values"]["reference"])
    assert not [t for t in titles if "_" in re.sub(r"\$[^$]*\$", "", t)], titles
    assert "$a_{\\mathrm{eq110}}$ x" in titles
    assert f"tolerance {result.spec['tolerance']['pointwise']['value']:g}" in [
        text.get_text() for text in drawn["fig"].legends[0].get_texts()]
    style.pyplot().close(drawn["fig"])


def chain_like(n):
    """Saved results and a case of n coordinates as the case page's figures read them: every source's run of two
    seconds (each off the tight one by its own small amount) and a pointwise sample."""
    from types import SimpleNamespace

    import numpy as np
    import pandas as pd

    from dyncheck.results.values import Outcome
    coords = [f"theta{k + 1}" for k in range(n)]
    t = np.linspace(0.0, 2.0, 201)
    run = lambda off: pd.DataFrame({c: np.sin((k + 1) * t) * (1 + off) + off for k, name in enumerate(coords)
                                    for c in (name, f"{name}_rate")}, index=pd.Index(t, name="t"))
    runs = {"reference": Outcome(run(1e-9), run(0.0)), "book": Outcome(run(2e-9)),
            "pinocchio": Outcome(run(3e-9)), "mujoco": Outcome(run(4e-7))}
    values = {source: {f"{c}_acc": np.linspace(1.0, 2.0, 16) * (1 + off) for c in coords}
              for source, off in (("reference", 0.0), ("book", 1e-15), ("mujoco", 1e-14), ("pinocchio", 2e-14))}
    result = SimpleNamespace(runs=runs, sample={"values": values, "states": [None] * 16})
    case = SimpleNamespace(spec={"title": f"A planar chain of {n} point masses"}, coords=coords,
                           tolerance={"pointwise": {"value": 1e-9}})
    return result, case


def drawn_series(result, case, columns, path, **options):
    """figure_series drawn and saved: its panels' x labels, and whether any two of their y labels overlap as laid
    out (style.save refuses a text off the figure, not one over another)."""
    from dyncheck.pages import figures
    drawn = {}
    save = figures.save

    def keep(fig, path):
        fig.draw_without_rendering()
        boxes = [ax.yaxis.label.get_window_extent() for ax in fig.axes]
        drawn.update(labels=[ax.get_xlabel() for ax in fig.axes],
                     overlap=any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1:]))
        save(fig, path)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(figures, "save", keep)
        figures.figure_series(result, case, columns, lambda c: f"|{figures.quantity_label(c)} error| [rad/s]",
                              path.stem, path, words={}, **options)
    return drawn["labels"], drawn["overlap"]


@pytest.mark.parametrize("n", range(1, 10))
def test_the_coordinate_figure_of_n_coordinates_prints(tmp_path, n):
    """Issue 37: a coordinate figure of an odd count above 3 (a panel left over in its last row) was refused,
    "'t [s]' runs off the figure's edge": the switched-off panel kept its label, which the layout placed below the
    figure.  For 1 to 9 coordinates the figure prints (style.save refuses what would not), a panel each, every
    column of panels with its time axis labelled."""
    result, case = chain_like(n)
    labels, overlap = drawn_series(result, case, case.coords, tmp_path / "coordinates.png")
    assert len(labels) == n and labels.count("t [s]") == (2 if n > 3 else 1) and not overlap
    assert (tmp_path / "coordinates.pdf").is_file()


@pytest.mark.parametrize("n", [5, 9])
def test_the_error_and_pointwise_figures_of_many_coordinates_print(tmp_path, n):
    """The same for the errors (a panel per coordinate and rate: 18 for 9 coordinates, their labels on two lines) and
    the pointwise figure (four panels across: 5 and 9 leave panels over)."""
    from dyncheck.pages import figures
    from dyncheck.run.simulate import state_columns
    result, case = chain_like(n)
    labels, overlap = drawn_series(result, case, state_columns(case), tmp_path / "errors.png", log_error=True)
    assert len(labels) == 2 * n and labels.count("t [s]") == 2 and not overlap
    figures.figure_pointwise(result, case, tmp_path / "pointwise.png", words={})
    assert {p.name for p in tmp_path.iterdir()} == {"errors.png", "errors.pdf", "pointwise.png", "pointwise.pdf"}
