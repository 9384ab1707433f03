"""Every figure prints: rendered from this session's runs of the book's cases and the examples, each PNG has
its vector PDF twin and fits the page's text width, and every figure on every page has its caption
(dyncheck.style.embed).  dyncheck.style.save refuses what would not print."""

import re

import pytest

from dyncheck import style



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
