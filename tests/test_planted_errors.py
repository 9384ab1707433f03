"""Planted errors (issue 13): how often does dyncheck name the term a wrong equation lacks?

Single-term errors (tests/planting.py) are planted in the code that computes the accelerations of the
book's cases with coordinates and of docs/own-case.md's cart-pendulum, and each mutant's equations are
checked as `dyncheck run` checks them (pointwise, per-equation residuals, localisation), without the
runs, which add nothing to where the error is.  A mutant is
  no effect  every equation row passes (it hit only the reactions or the energy, or a term that vanishes)
  detected   an equation row fails
  named      detected, and every equation the error changes, and no other, has a localisation that is
             exact and whose every coefficient is a product of the parameters.
A named term is the right term: exact means the fitted terms cancel the mutant's residual to the
engines' rounding at every state of every parameter set (~50 states x 9 sets for at most 3 terms),
and that residual is the planted change itself, since the unmutated derivation's residual is at
rounding (checked: `test_the_subjects_pass_unmutated`); two texts that agree at all those random
states are one function (a trigonometric identity at most, which TermFit reports as an alternative).
"""

import re
import shutil
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from dyncheck.case.folder import Case
from dyncheck.checks import pointwise, residuals
from dyncheck.results.values import Status
import planting
from test_own_case_doc import steps

ROOT = Path(__file__).resolve().parent.parent
# The functions that compute each book case's accelerations (the others' joints are all driven: no
# equations of motion).  Their modules import reference.* absolutely, so a mutant runs from the copied
# case folder.  The reference's kinematic chain (reference/spinning_base.py) is not planted in, nor the
# double pendulum, whose equations are the book's printed expressions as strings compiled once
# (reference/double_pendulum.py): no operand of its code is a term.
BOOK = {"spring_pendulum": ("Book.accelerations", "Reference._motion"),
        "rotating_pendulum": ("Book.accelerations", "Reference._motion"),
        "spinning_top": ("Book.accelerations", "Book._cm_inertias")}
TUTORIAL = "cart_pendulum"
TUTORIAL_FUNCTIONS = ("mass_matrix", "forces")
OUT = Path("/tmp/dyncheck_planted")


@dataclass(frozen=True)
class Subject:
    """A case whose derivation errors are planted in: its folder, the derivation's file in a copy of the
    folder and its source, the functions planted in."""
    name: str
    folder: Path
    file: str
    source: str
    functions: tuple

    def planted(self, mutant, where):
        """A copy of the case folder in `where` with the mutant as its derivation."""
        folder = where / self.name
        shutil.copytree(self.folder, folder)
        (folder / self.file).write_text(mutant.source)
        if self.file != "equations.py":  # a book case: its case file names the mutant
            toml = folder / "case.toml"
            text, count = re.subn(r'^derivation = "reference\.\w+"$', f'derivation = "{self.file}"',
                                  toml.read_text(), flags=re.M)
            assert count == 1, f"{toml}: no single derivation line"
            toml.write_text(text)
        return folder


def book_subject(name):
    return Subject(name, ROOT / "cases" / name, "mutant.py", (ROOT / "reference" / f"{name}.py").read_text(),
                   BOOK[name])


def tutorial_subject(where, functions=TUTORIAL_FUNCTIONS):
    """docs/own-case.md's case as the guide writes it, before its planted error."""
    for kind, path, text in steps():
        if kind == "file" and path.startswith(TUTORIAL + "/"):
            (where / path).parent.mkdir(parents=True, exist_ok=True)
            (where / path).write_text(text)
    folder = where / TUTORIAL
    return Subject(TUTORIAL, folder, "equations.py", (folder / "equations.py").read_text(), functions)


# The tutorial's cart-pendulum as a derivation that gives its accelerations only, solved in closed form from M and
# f written entry by entry (as a symbolic package prints them): an error in an entry of M shows only through q''.
CLOSED_FORM = '''"""Cart on a spring with a hanging pendulum, its accelerations in closed form."""
import numpy as np

COORDS = ["x", "theta"]
PARAMS = {"M": 1.0, "m": 0.3, "l": 0.5, "k": 20.0, "g": 9.81}


def accelerations(t, q, v, p):
    x, theta = q
    x_rate, theta_rate = v
    M, m, l, k, g = p["M"], p["m"], p["l"], p["k"], p["g"]
    m11 = M + m
    m12 = m * l * np.cos(theta)
    m22 = m * l**2
    f1 = m * l * np.sin(theta) * theta_rate**2 - k * x
    f2 = -m * g * l * np.sin(theta)
    det = m11 * m22 - m12 * m12
    return np.array([(m22 * f1 - m12 * f2) / det, (m11 * f2 - m12 * f1) / det])
'''


def closed_form_subject(where):
    """The tutorial's scene with CLOSED_FORM as its derivation; errors planted in its entries of M and f."""
    folder = tutorial_subject(where).folder
    (folder / "equations.py").write_text(CLOSED_FORM)
    return Subject(f"{TUTORIAL}_closed_form", folder, "equations.py", CLOSED_FORM, ("accelerations",))


# A rigid-body subject: two rigid links on hinges (an acrobot hanging), each with its inertia about its centre of mass
# a parameter bound to the scene's diaginertia, as Spong's benchmark writes them (q2 the elbow's relative angle, both
# from the downward vertical; a positive angle swings towards +x about the hinges' -y axes, as in tests/chain.py).
ACROBOT_SCENE = """<mujoco model="acrobot">
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="upper">
      <joint name="q1" type="hinge" axis="0 -1 0"/>
      <inertial pos="0 0 -0.22" mass="1.1" diaginertia="0.032 0.031 0.002"/>
      <body name="lower" pos="0 0 -0.5">
        <joint name="q2" type="hinge" axis="0 -1 0"/>
        <inertial pos="0 0 -0.27" mass="0.9" diaginertia="0.025 0.024 0.0015"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""
ACROBOT_PARAMS = """COORDS = ["q1", "q2"]
PARAMS = {"m1": 1.1, "m2": 0.9, "l1": 0.5, "lc1": 0.22, "lc2": 0.27, "I1": 0.031, "I2": 0.024, "g": 9.81}
"""
ACROBOT_MASS = '''    m11 = I1 + I2 + m1 * lc1**2 + m2 * (l1**2 + lc2**2 + 2 * l1 * lc2 * np.cos(q2))
    m12 = I2 + m2 * (lc2**2 + l1 * lc2 * np.cos(q2))
    m22 = I2 + m2 * lc2**2
'''
ACROBOT_FORCES = '''    f1 = (m2 * l1 * lc2 * np.sin(q2) * (2 * q1_rate * q2_rate + q2_rate**2) - (m1 * lc1 + m2 * l1) * g * np.sin(q1)
          - m2 * lc2 * g * np.sin(q1 + q2))
    f2 = -m2 * l1 * lc2 * np.sin(q2) * q1_rate**2 - m2 * lc2 * g * np.sin(q1 + q2)
'''
UNPACK = '''    q1, q2 = q
    m1, m2, l1, lc1, lc2, I1, I2, g = (p[name] for name in ("m1", "m2", "l1", "lc1", "lc2", "I1", "I2", "g"))
'''
RATES = "    q1_rate, q2_rate = v\n"
ACROBOT = ('"""An acrobot hanging: two rigid links, inertias about their centres of mass (Spong\'s equations)."""\n'
           "import numpy as np\n\n" + ACROBOT_PARAMS + "\n\ndef mass_matrix(q, p):\n" + UNPACK
           + ACROBOT_MASS + "    return np.array([[m11, m12], [m12, m22]])\n\n\ndef forces(t, q, v, p):\n" + UNPACK + RATES
           + ACROBOT_FORCES + "    return np.array([f1, f2])\n\n\ndef accelerations(t, q, v, p):\n"
           "    return np.linalg.solve(mass_matrix(q, p), forces(t, q, v, p))\n")
# The same acrobot with its accelerations only, solved by Cramer's rule from M and f written entry by entry.
ACROBOT_CLOSED_FORM = ('"""An acrobot hanging, its accelerations in closed form (Cramer\'s rule on Spong\'s M and f)."""\n'
                       "import numpy as np\n\n" + ACROBOT_PARAMS + "\n\ndef accelerations(t, q, v, p):\n" + UNPACK + RATES
                       + ACROBOT_MASS + ACROBOT_FORCES + "    det = m11 * m22 - m12 * m12\n"
                       "    return np.array([(m22 * f1 - m12 * f2) / det, (m11 * f2 - m12 * f1) / det])\n")


def acrobot_subject(where, closed_form=False):
    """The rigid acrobot from two files: errors planted in M and f, or (closed_form) in its accelerations alone."""
    name = "acrobot_closed_form" if closed_form else "acrobot"
    folder = where / name
    folder.mkdir(parents=True)
    (folder / "scene.xml").write_text(ACROBOT_SCENE)
    source = ACROBOT_CLOSED_FORM if closed_form else ACROBOT
    (folder / "equations.py").write_text(source)
    return Subject(name, folder, "equations.py", source, ("accelerations",) if closed_form else TUTORIAL_FUNCTIONS)


@dataclass(frozen=True)
class Verdict:
    case: str
    mutant: planting.Mutant
    changed: tuple  # (source, equation) the planted error changes beyond the pointwise tolerance
    failing: tuple  # the equation rows that fail: (check quantity, sources)
    localisations: tuple

    @property
    def detected(self):
        return bool(self.failing)

    @property
    def miss(self):
        """Why a detected error is not named; None when it is (or when it is not detected)."""
        if not self.detected:
            return None
        if {(l.source, l.equation) for l in self.localisations} != set(self.changed):
            return "localised in other equations than those changed"
        exact = [l.exact for l in self.localisations]
        if not any(exact):
            return "no exact fit"
        if not all(exact):
            return "exact in some equations only"
        if not all(l.identified for l in self.localisations):
            return "a coefficient is no product of parameters"
        return None

    @property
    def named(self):
        return self.detected and self.miss is None

    @property
    def outcome(self):
        return "named" if self.named else "detected" if self.detected else "no effect"


def equations(case):
    """dyncheck's equation rows of a case, their residuals against the engines and the localisations."""
    _, sample = pointwise.pointwise(case)
    rows, found = residuals.equation_rows(case, sample)
    return sample, rows, residuals.localise(case, rows, found, pointwise.parameter_sets(case)[0])


def judge(subject, mutant, where):
    original, case = Case(subject.folder), Case(subject.planted(mutant, where))
    sample, rows, localisations = equations(case)
    tolerance = case.tolerance["pointwise"]["value"]
    changed = []
    for source in residuals.derivation_sources(case):
        before = residuals.residuals(original, source, "mujoco", sample["states"])
        if source in sample["failures"]:  # the mutant cannot be evaluated: every equation changed
            changed += [(source, c) for c in case.coords]
            continue
        mutated = residuals.residuals(case, source, "mujoco", sample["states"])
        if before.given_mass is not None and before.given_forces is not None:
            # M and f given: an equation changes where its row of M or its f does (an error in M[x,x] changes
            # both accelerations, but only the x equation), each relative to its own row's size as dyncheck judges it
            mass_change = np.nan_to_num(np.max(np.abs(mutated.given_mass - before.given_mass), axis=2), nan=np.inf)
            force_change = np.nan_to_num(np.abs(mutated.given_forces - before.given_forces), nan=np.inf)
            changed += [(source, c) for i, c in enumerate(case.coords)
                        if np.max(mass_change[:, i]) > tolerance * np.max(np.abs(before.mass))
                        or np.max(force_change[:, i]) > tolerance * before.of(("residual", i))[1]]
            continue
        after = before.mass @ residuals.accelerations_of(sample["values"][source], case)[:, :, None]
        change = np.abs(after[:, :, 0] - before.derivation_forces)
        changed += [(source, c) for i, c in enumerate(case.coords)
                    if np.max(change[:, i]) > tolerance * before.of(("residual", i))[1]]
    failing = tuple((r.quantity, r.sources) for r in rows if r.status == Status.FAIL)
    return Verdict(subject.name, mutant, tuple(changed), failing, localisations)


def test_the_subjects_pass_unmutated(tmp_path):
    """Every planted error is measured against a derivation whose equations agree with the engines."""
    for subject in [book_subject(name) for name in BOOK] + [tutorial_subject(tmp_path), acrobot_subject(tmp_path),
                                                            acrobot_subject(tmp_path, closed_form=True)]:
        _, rows, localisations = equations(Case(subject.folder))
        assert [r for r in rows if r.status != Status.PASS] == [] and localisations == (), subject.name


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_four_planted_errors_in_the_tutorial_are_named(tmp_path):
    """One error of each kind in the cart-pendulum's force side, as the issue asks: each detected, and
    its wrong equation named with the term."""
    subject = tutorial_subject(tmp_path / "original", functions=("forces",))
    mutants = planting.mutants(subject.source, subject.functions, per_kind=1, seed=13)
    assert sorted(m.kind for m in mutants) == sorted(planting.KINDS)
    for number, mutant in enumerate(mutants):
        verdict = judge(subject, mutant, tmp_path / f"mutant{number}")
        assert verdict.named, (str(mutant), verdict.changed, verdict.failing, [str(l) for l in verdict.localisations])


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_an_entry_of_m_wrong_inside_closed_form_accelerations_is_named_as_m_s(tmp_path):
    """m left out of M + m (M11) inside accelerations written in closed form: the x equation's residual is
    -m x''_d, a term in the derivation's own acceleration, named with M's column; nothing else is named."""
    subject = closed_form_subject(tmp_path / "original")
    mutant = next(m for m in planting.mutants(subject.source, subject.functions, per_kind=50, seed=1)
                  if m.kind == "drop" and m.term == "m" and "m11 =" in subject.source.splitlines()[m.line - 1])
    verdict = judge(subject, mutant, tmp_path / "mutant")
    assert verdict.named, (str(mutant), verdict.changed, verdict.failing, [str(l) for l in verdict.localisations])
    (localisation,) = verdict.localisations
    assert "m x''" in localisation.text and "entry in its column x lacks + m" in localisation.text, localisation.text


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_a_wrong_determinant_is_not_explained_by_the_engines_whole_equation(tmp_path):
    """m11 m22 dropped from det M scales both accelerations: with q''_d among the candidates, the theta equation's
    residual m l cos(theta) x''_d + m l^2 theta''_d + m g l sin(theta) is three terms, the engine's whole equation,
    which fits the residual of any wrong accelerations and names nothing: it is not given as the term."""
    subject = closed_form_subject(tmp_path / "original")
    mutant = next(m for m in planting.mutants(subject.source, subject.functions, per_kind=50, seed=1)
                  if m.kind == "drop" and m.term == "m11 * m22")
    verdict = judge(subject, mutant, tmp_path / "mutant")
    assert verdict.detected
    whole = [l.text for l in verdict.localisations if l.exact and "m l^2 theta''" in l.text and "x''" in l.text]
    assert whole == [], whole


@pytest.mark.slow
def test_campaign(tmp_path):
    """>= 100 seeded planted errors over the four book cases with coordinates, the tutorial and its closed form
    (accelerations only, CLOSED_FORM), and a rigid acrobot (inertias about the centres of mass as parameters) in
    both forms: a table
    per case and kind (printed, and saved to /tmp/dyncheck_planted/).  Every error that changes an
    equation is detected; the hit rate named / detected is measured, not asserted."""
    start = time.perf_counter()
    subjects = [book_subject(name) for name in BOOK] + [tutorial_subject(tmp_path / "original"),
                                                        closed_form_subject(tmp_path / "closed form"),
                                                        acrobot_subject(tmp_path / "rigid"),
                                                        acrobot_subject(tmp_path / "rigid", closed_form=True)]
    verdicts = []
    for subject in subjects:
        mutants = planting.mutants(subject.source, subject.functions, per_kind=8, seed=2024)
        assert mutants, f"{subject.name}: no term to plant an error in ({', '.join(subject.functions)})"
        for mutant in mutants:
            verdicts.append(judge(subject, mutant, tmp_path / f"mutant{len(verdicts)}"))
    wall = time.perf_counter() - start
    frame = pd.DataFrame({"case": v.case, "kind": v.mutant.kind, "outcome": v.outcome, "miss": v.miss,
                          "mutant": str(v.mutant), "changed": " ".join(f"{s}:{c}" for s, c in v.changed),
                          "localisations": " | ".join(str(l) for l in v.localisations)} for v in verdicts)
    table = pd.concat([tally(frame), tally(frame.assign(kind="all")), tally(frame.assign(case="all", kind="all"))])
    OUT.mkdir(parents=True, exist_ok=True)
    table.to_csv(OUT / "campaign.csv")
    frame.to_csv(OUT / "mutants.csv", index=False)
    print(f"\n{table.to_string()}\n\n{len(verdicts)} mutants in {wall:.0f} s; per mutant: {OUT / 'mutants.csv'}")
    print(f"misses by reason:\n{frame.groupby(['case', 'miss']).size().to_string()}")
    assert len(verdicts) >= 100
    assert [str(v.mutant) for v in verdicts if v.changed and not v.detected] == []
    assert [str(v.mutant) for v in verdicts if v.detected and not v.changed] == []


def tally(frame):
    """Per case and kind: mutants, no effect, detected, named, and the hit rate named / detected."""
    table = frame.groupby(["case", "kind"]).outcome.agg(mutants="size", no_effect=lambda o: (o == "no effect").sum(),
                                          detected=lambda o: (o != "no effect").sum(),
                                          named=lambda o: (o == "named").sum())
    table["hit rate"] = (table.named / table.detected).round(3)
    return table
