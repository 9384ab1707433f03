"""The student's pages (dyncheck/pages/student_page.py): every book example has one, every step that shows an
expression has it typeset and checked, the words are a student's, and a [course] that names what the case does not
have is refused."""

import re
import shutil
from types import SimpleNamespace

import pytest

import dyncheck
from dyncheck.pages import student_page

BOOK = ("piston", "rotating_pendulum", "rotating_particle", "spring_pendulum", "double_pendulum", "spinning_top")
JARGON = re.compile(r"\b(armature|rollout|placeholder|rows?|tolerance ceiling|ceiling)\b", re.IGNORECASE)


@pytest.fixture(scope="module")
def pages(rendered):
    """Every book example's student page, rendered with the validation pages (conftest.rendered)."""
    return rendered / "reports"


def sections(page):
    """{step number: its text} of a student's page."""
    parts = re.split(r"^## (\d+)\. .*$", page, flags=re.MULTILINE)
    return {int(number): text for number, text in zip(parts[1::2], parts[2::2])}


@pytest.mark.parametrize("name", BOOK)
def test_every_book_example_has_a_student_page_with_each_result_typeset_and_checked(pages, name):
    case = dyncheck.load_case(name)
    page = (pages / student_page.page_name(case)).read_text()
    steps = sections(page)
    course = student_page.course(case)
    assert len(steps) == len(course.steps) == 9
    for number, step in enumerate(course.steps, 1):
        text = steps[number]
        expressions = [s for s in step.shown if s.expression]
        assert text.count("\n$$") >= len(expressions), (name, step.title)
        if expressions:
            assert "*Check" in text, (name, step.title)
    assert f"({student_page.page_name(case)})" in (pages / f"{name}.md").read_text()
    assert f"({student_page.page_name(case)})" in (pages / "index.md").read_text()


@pytest.mark.parametrize("name", BOOK)
def test_the_page_speaks_a_students_words(pages, name):
    page = (pages / f"{name}_student.md").read_text()
    assert not JARGON.search(page), JARGON.search(page)
    assert page.count("$") % 2 == 0  # every inline maths closed
    assert not re.search(r"\\\\[a-zA-Z]", page)  # a backslash doubled by a TOML basic string: \\psi
    assert "np.float64" not in page and "array(" not in page


def test_a_finding_shows_the_printed_and_the_right_expression_with_the_difference_boxed():
    case = dyncheck.load_case("spring_pendulum")
    shown = next(s for step in student_page.course(case).steps for s in step.shown if s.expression == "book:R")
    printed = case.derivation.Book.PRINTED["R"]
    right = printed.replace("L*psi_rate", "2*L*psi_rate")
    finding = SimpleNamespace(id="1.8.3-R", pairs=(SimpleNamespace(printed=printed, right=right),))
    lines = student_page.maths(case, SimpleNamespace(findings=(finding,)), shown)
    maths = [line for line in lines if line.startswith("$$R = ")]
    assert len(maths) == 2 and r"\boxed{2}" in maths[1]  # the printed R, then the right one with its 2 boxed
    assert any("errata.md#183-r" in line for line in lines)


def edited(tmp_path, name, old, new):
    """A copy of a book case whose case.toml has `old` replaced by `new`."""
    folder = tmp_path / name
    shutil.copytree(f"cases/{name}", folder)
    text = (folder / "case.toml").read_text()
    assert old in text
    (folder / "case.toml").write_text(text.replace(old, new, 1))
    return folder


def test_a_course_naming_an_unknown_quantity_is_refused_on_load(tmp_path):
    edited(tmp_path, "spring_pendulum", 'quantities = ["Newton Y3 (1.8.3)"]', 'quantities = ["Newton Q3"]')
    with pytest.raises(ValueError, match=r"case\.toml: course\.steps\[4\]\.show\[1\]\.quantities = 'Newton Q3'"):
        dyncheck.load_case("spring_pendulum", cases_dir=tmp_path)


def test_a_course_naming_an_unknown_expression_is_refused(tmp_path):
    edited(tmp_path, "spring_pendulum", 'expression = "book:a_C"', 'expression = "book:a_Q"')
    case = dyncheck.load_case("spring_pendulum", cases_dir=tmp_path)
    with pytest.raises(ValueError, match=r"course\.steps\[3\]\.show\[0\]\.expression = 'book:a_Q'.*no book expression"):
        student_page.course(case)


def test_a_figure_not_drawn_because_the_reference_run_ran_away_is_said_so(tmp_path):
    # `dyncheck report spring_pendulum --set k=100`: the spring too soft for the spin, the run leaves its bound and
    # the case page draws nothing along it; the student page said so by a ValueError (a traceback, no report)
    case = dyncheck.load_case("spring_pendulum", k=100.0)
    step = SimpleNamespace(title="The scene", text="", shown=(), vibration=False, figures=(("scene", "the scene"),))
    ran_away = SimpleNamespace(runs={"reference": SimpleNamespace(ok=False)}, rows=())
    assert "(The figure 'scene' is not in this report: it is drawn along the reference run, which did not reach its " \
           "end; the case page says why.)" in student_page.step_lines(1, step, case, ran_away, tmp_path)
    # a figure a --set left undrawn otherwise (no oscillating mode to draw the shapes of, ...)
    whole = SimpleNamespace(runs={"reference": SimpleNamespace(ok=True)}, rows=())
    assert "(The figure 'scene' is not in this report: the case page could not draw it at these parameters; the case " \
           "page says why.)" in student_page.step_lines(1, step, case, whole, tmp_path)
    # at the book's numbers every figure a course names is drawn: one that is not, the case never draws
    with pytest.raises(ValueError, match="figure 'scene': the case page drew no"):
        student_page.step_lines(1, step, dyncheck.load_case("spring_pendulum"), whole, tmp_path)
