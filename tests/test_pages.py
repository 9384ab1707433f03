"""Every page of both report trees, rendered from this session's runs as `dyncheck report` writes them, reads as prose and
tables: no Python or numpy repr, no NaN or None shown as a value, no empty field or table cell, no
bracket reference that links nowhere, no relative link to a file the tree lacks, no "1 cases" or
"16 finding" (issue 16).  Each failure names the page and the line."""

import re
from dataclasses import replace
from types import SimpleNamespace

import pandas as pd
import pytest

from dyncheck.case.scene import Driven
from dyncheck.case.units import registry
from dyncheck.common.messages import statuses_in_words
from dyncheck.pages.case_page import as_written, law_of_time, markdown_table, random_tried, worst_engine_error
from dyncheck.results.values import OWN_WORDS, Row, Status
from test_ci_contract import toy

# The nouns the pages count, singular and plural, for "1 cases" and "16 finding".
NOUNS = "case|row|finding|check|state|set|parameter|run|edit|quantity|source|method|figure|runaway|step|mode"
PLURALS = ("cases|rows|findings|checks|states|sets|parameters|runs|edits|quantities|sources|methods|figures|"
           "runaways|steps|modes")
DEFECTS = [  # (what is wrong, a pattern that shows it in a line of prose or a table row)
    ("a Python or numpy repr", re.compile(r"\bnp\.\w+\(|\barray\(|\bdtype\b|\bobject at 0x")),
    ("NaN or None shown as a value",
     re.compile(r"(?<![\w'-])(?:nan|NaN)(?![\w'-])|(?:^\s*|[=:(]\s*)None\s*(?:$|[,;.)])")),
    ("an empty field", re.compile(r"[:=]\s*[,;]|\(\s*\)|^\s*[,;]")),
    ("a count that disagrees with its noun",
     re.compile(rf"(?<![\d.,-])\b1 (?:{PLURALS})\b"
                rf"|(?<![\d.,-])\b(?:0|[2-9]|\d\d+) (?:{NOUNS})\b(?![-'])")),
]
REFERENCE = re.compile(r"(?<![\w\]!\\])\[{1,2}([A-Za-z_][\w.]*)\]{1,2}(?![(\[])")  # [word] or [[word]], no link
LINK = re.compile(r"\]\(([^)\s]+)\)")


@pytest.fixture(scope="module")
def pages(rendered):
    """{page: its file} of both report trees, rendered from this session's runs (conftest.rendered)."""
    return {path.relative_to(rendered): path for path in sorted((rendered / "reports").rglob("*.md"))}


def prose_lines(path):
    """(number, line) of a page outside fenced code blocks, each inline code span and formula a word."""
    fenced = False
    for number, line in enumerate(path.read_text().splitlines(), 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
        elif not fenced:
            yield number, re.sub(r"`[^`]*`|\$\$.*?\$\$|\$[^$]*\$", "code", line)


def cells(line):
    """The cells of a Markdown table row (a | escaped as \\| stays in its cell), or none for other lines."""
    return re.split(r"(?<!\\)\|", line.strip())[1:-1] if line.lstrip().startswith("|") else []


def test_no_page_shows_a_repr_an_empty_field_or_a_wrong_plural(pages):
    found = []
    for page, path in pages.items():
        for number, line in prose_lines(path):
            parts = cells(line) or [line]
            found += [f"{page}:{number}: {what}: {line.strip()[:160]}" for what, pattern in DEFECTS
                      if any(pattern.search(part) for part in parts)]
            if any(not cell.strip() for cell in cells(line)):
                found.append(f"{page}:{number}: an empty table cell: {line.strip()[:160]}")
    assert not found, "\n".join(found)


def is_unit(word):
    try:
        registry().parse_units(word)
    except Exception:  # pint's parser fails in many ways
        return False
    return True


def test_every_bracket_is_a_link_and_every_link_resolves(pages):
    found = []
    for page, path in pages.items():
        for number, line in prose_lines(path):
            found += [f"{page}:{number}: [{word}] refers to nothing a reader of the page can follow"
                      for word in REFERENCE.findall(line) if not is_unit(word) and word not in ("x", "X")]  # checkboxes
            for target in LINK.findall(line):
                file = target.split("#")[0]
                if file and "://" not in file and not (path.parent / file).exists():
                    found.append(f"{page}:{number}: the link {target} names no file")
    assert not found, "\n".join(found)


def test_a_table_shows_text_as_written_and_nothing_as_a_dash():
    table = markdown_table(pd.DataFrame({"step [s]": ["0.0200"], "finding": [""], "error": [float("nan")],
                                         "|a - b|": ["|x|"], "count": [3]}))
    assert table.splitlines()[0].split() == ["|", "step", "[s]", "|", "finding", "|", "error", "|", "\\|a", "-",
                                             "b\\|", "|", "count", "|"]
    assert table.splitlines()[2].split() == ["|", "0.0200", "|", "-", "|", "-", "|", "\\|x\\|", "|", "3", "|"]


def test_counts_agree_with_their_nouns():
    assert statuses_in_words({"pass": 1, "finding": 16, "fail": 0, "runaway": 1}) == "1 pass, 16 findings, 1 runaway"
    assert law_of_time(Driven(0.8, 0.3, -0.1)) == "0.8 + 0.3 t - 0.05 t^2" and law_of_time(Driven(0.0, 1.5, 0.0)) == "1.5 t"


def test_a_wrong_derivation_is_no_agreement_on_the_index():
    """A researcher's case names its reference "derivation" (in_own_words): its failing pointwise rows are the
    index's disagreement and its worst engine error, not left out as a source that is no engine."""
    wrong = row_of("pointwise", "theta''", (OWN_WORDS["reference"], "mujoco"), 0.3, Status.FAIL)
    agreeing = row_of("pointwise", "theta''", ("mujoco", "pinocchio"), 1e-15, Status.PASS)
    result = replace(toy("own", failing=False), rows=(wrong, agreeing))
    case = SimpleNamespace(spec=result.spec)
    assert random_tried(result, case)["agreed"] is False
    assert worst_engine_error(result.rows) == 0.3


def row_of(check, quantity, sources, error, status):
    return Row(check, quantity, sources, error, 1e-9, 1e-6, status)


def test_a_docstring_s_matrix_keeps_its_lines_and_its_prose_its_paragraphs():
    text = ("A cart and a pendulum.\n"
            "Lagrange's equations give\n\n"
            "    M(q) = [[M + m,          m l cos(theta)],\n"
            "            [m l cos(theta), m l^2         ]]\n\n"
            "- x: the cart\n- theta: the rod\n")
    assert as_written(text).split("\n\n") == [
        "A cart and a pendulum. Lagrange's equations give",
        "```text\nM(q) = [[M + m,          m l cos(theta)],\n        [m l cos(theta), m l^2         ]]\n```",
        "- x: the cart\n- theta: the rod"]
