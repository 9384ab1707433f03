"""dyncheck.pages.typeset: the expressions the code evaluates, as LaTeX, and two versions with what differs boxed."""

import importlib

import pytest

from dyncheck.pages.typeset import latex, marked

BOOKS = [(module, cls) for module in ("piston", "rotating_pendulum", "rotating_particle", "spring_pendulum",
                                      "double_pendulum", "spinning_top")
         for cls in ("Book", "Program") if hasattr(importlib.import_module(f"reference.{module}"), cls)]


@pytest.mark.parametrize("module, cls", BOOKS)
def test_every_printed_expression_renders(module, cls):
    book = getattr(importlib.import_module(f"reference.{module}"), cls)
    for key, expression in getattr(book, "PRINTED", {}).items():
        text = latex(expression, getattr(book, "LATEX", None))
        assert text.count("{") == text.count("}"), (key, text)
        assert text.count(r"\left(") == text.count(r"\right)"), (key, text)
        assert "$" not in text and "*" not in text and "_rate" not in text, (key, text)


@pytest.mark.parametrize("expression, expected", [
    ("a - (b + c)", r"a - \left(b + c\right)"),
    ("a + (b + c)", r"a + \left(b + c\right)"),  # the printed bracket kept
    ("-(x)**2", "-x^2"),
    ("(-x)**2", r"\left(-x\right)^2"),
    ("(a + b)/c", r"\frac{a + b}{c}"),
    ("-k/m*l", r"-\frac{k}{m} l"),
    ("a*(-b)", r"a \left(-b\right)"),
    ("-m*(a + b)", r"-m \left(a + b\right)"),
    ("2*3*x", r"2 \cdot 3 x"),
    ("2*L_rate*psi_rate*cos(psi)", r"2 \dot{L} \dot{\psi} \cos \psi"),
    ("sin(psi)**2", r"\sin^2 \psi"),
    ("cos(alpha + beta)", r"\cos \left(\alpha + \beta\right)"),
    ("(a + b)**2", r"\left(a + b\right)^2"),
    ("x**(n + 1)", "x^{n + 1}"),
    ("5e-05", r"5 \cdot 10^{-5}"),
    ("2.0*x", "2 x"),
    ("array([x, y, 0.0])", r"\begin{bmatrix} x \\ y \\ 0 \end{bmatrix}"),
    ("array([[a, b], [c, d]]) @ v", r"\begin{bmatrix} a & b \\ c & d \end{bmatrix} v"),
    ("A.T @ B", "{A}^T B"),
    ("sqrt(k/m)", r"\sqrt{\frac{k}{m}}"),
    ("Izz <= 2*Ixx", r"I_{zz} \le 2 I_{xx}"),
    ("-0.8 <= theta2 <= 0.8", r"-0.8 \le \theta_{2} \le 0.8"),
])
def test_latex(expression, expected):
    assert latex(expression) == expected


@pytest.mark.parametrize("name, expected", [
    ("psi", r"\psi"), ("Omega", r"\Omega"), ("psi_rate", r"\dot{\psi}"), ("psi_acc", r"\ddot{\psi}"),
    ("alpha_rate", r"\dot{\alpha}"), ("x_rate", r"\dot{x}"), ("l0", "l_{0}"), ("lo", "l_0"), ("a_E", "a_{E}"),
    ("Ixx", "I_{xx}"), ("theta1", r"\theta_{1}"), ("tempo", r"\mathit{tempo}"),
])
def test_default_symbols(name, expected):
    assert latex(name) == expected


def test_a_module_table_overrides_the_defaults_and_takes_arguments():
    assert latex("TzT(p) @ v", {"TzT": "T_z({})^T", "p": r"\varphi"}) == r"T_z(\varphi)^T v"
    assert latex("d1**2", {"d1": r"\dot{\theta}_1"}) == r"\dot{\theta}_1^2"


@pytest.mark.parametrize("expression", ["x[0]", "f(x=1)", "x if y else z", "'text'", "a < b in c", "lambda: 1",
                                        "sqrt(a, b)", "a +"])
def test_unknown_syntax_is_refused_with_a_clear_message(expression):
    with pytest.raises(ValueError, match="cannot typeset"):
        latex(expression)


@pytest.mark.parametrize("printed, right, expected", [
    # a changed factor is boxed where it changed
    ("2*Ld*w*sin(th) + a", "2*Ld*w*cos(th) + a",
     (r"2 \mathit{Ld} w \boxed{\sin \mathit{th}} + a", r"2 \mathit{Ld} w \boxed{\cos \mathit{th}} + a")),
    # an added term alone, a dropped term alone
    ("a + b", "a + b + c", ("a + b", r"a + b + \boxed{c}")),
    ("a + b*c - d", "a - d", (r"a + \boxed{b c} - d", "a - d")),
    # a factor added, a sign flipped (the sign boxed with its term)
    ("a + b*c - d", "a + 2*b*c + d", (r"a + b c \boxed{- d}", r"a + \boxed{2} b c \boxed{+ d}")),
    # inside a column: only the component that differs
    ("array([x, y*sin(p)])", "array([x, y*cos(p)])",
     (r"\begin{bmatrix} x \\ y \boxed{\sin p} \end{bmatrix}", r"\begin{bmatrix} x \\ y \boxed{\cos p} \end{bmatrix}")),
    ("x", "x", ("x", "x")),
])
def test_marked_boxes_exactly_what_differs(printed, right, expected):
    assert marked(printed, right) == expected


def test_the_errata_show_a_printed_and_a_right_side_for_every_finding(results, rendered):
    """Rendered from the saved results (conftest.rendered): every finding has at least one typeset pair,
    each display formula balanced, and the case file's right expressions pass their rows."""
    with_findings = [result for result in results.values() if result.findings]
    errata = (rendered / "reports" / "errata.md").read_text()
    for finding in [f for result in with_findings for f in result.findings]:
        section = errata.split(f"## {finding.id}\n", 1)[1].split("\n## ", 1)[0]
        assert "*As printed*" in section and "*Right*" in section, finding.id
        formulas = section.split("$$\n")[1::2]
        assert all(formula.count("{") == formula.count("}") for formula in formulas), finding.id
        pairs = zip(formulas[::2], formulas[1::2])  # as printed, right: what differs boxed on one side or both
        assert all(r"\boxed" in printed + right for printed, right in pairs), finding.id
    rights = [r for result in with_findings for r in result.rows if "finding's right" in r.sources]
    assert len(rights) == 2 and all(r.status.ok for r in rights), rights
