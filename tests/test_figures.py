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
