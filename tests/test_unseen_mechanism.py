"""A mechanism dyncheck has never seen, written from docs/own-case.md alone: an elastic pendulum.

A point mass m hangs from a fixed hinge on a massless spring of stiffness k and natural length L, in
polar coordinates: theta from the downward vertical, s the spring's extension (r = L + s).  Its two
files run green; each of four errors planted in its equations (a dropped term, a flipped sign, sin for
cos, a factor 2 lost) fails the run with the line naming the wrong equation and the missing term in the
derivation's own symbols.
"""

import json

import pytest

from dyncheck.cli import main

# The hinge's body carries only the hinge: MuJoCo wants a positive mass on every moving body, so it holds
# the 1e-14 placeholder, as the bob's point-mass inertia does.
SCENE = """\
<mujoco model="elastic_pendulum">
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="rod">
      <joint name="theta" type="hinge" axis="0 -1 0"/>
      <inertial pos="0 0 0" mass="1e-14" diaginertia="1e-14 1e-14 1e-14"/>
      <body name="bob">
        <joint name="s" type="slide" axis="0 0 -1" stiffness="30"/>
        <inertial pos="0 0 -0.8" mass="0.4" diaginertia="1e-14 1e-14 1e-14"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

EQUATIONS = '''\
"""Elastic pendulum in polar coordinates, derived by Lagrange's equations.

A point mass m hangs from a fixed hinge on a massless spring of stiffness k and natural length L;
theta is the spring's angle from the downward vertical (positive towards +x), s its extension, so
the bob is at r = L + s from the hinge:
T = m (s'^2 + r^2 theta'^2) / 2,  V = k s^2 / 2 - m g r cos(theta).
"""
import numpy as np

COORDS = ["theta", "s"]
PARAMS = {"m": 0.4, "L": 0.8, "k": 30.0, "g": 9.81}


def mass_matrix(q, p):
    theta, s = q
    m, r = p["m"], p["L"] + s
    return np.array([[m * r**2, 0.0],
                     [0.0, m]])


def forces(t, q, v, p):
    theta, s = q
    theta_rate, s_rate = v
    m, k, g, r = p["m"], p["k"], p["g"], p["L"] + s
    return np.array([-2 * m * r * s_rate * theta_rate - m * g * r * np.sin(theta),
                     m * r * theta_rate**2 - k * s + m * g * np.cos(theta)])


def accelerations(t, q, v, p):
    return np.linalg.solve(mass_matrix(q, p), forces(t, q, v, p))


def energy(t, q, v, p):
    theta, s = q
    theta_rate, s_rate = v
    m, k, g, r = p["m"], p["k"], p["g"], p["L"] + s
    kinetic = 0.5 * m * (s_rate**2 + r**2 * theta_rate**2)
    return kinetic + 0.5 * k * s**2 - m * g * r * np.cos(theta)
'''

# Each planted error: the text replaced in EQUATIONS, and the line of `dyncheck run` naming the term to
# add.  dyncheck's term library holds the lengths and the coordinates apart, so a term in r = L + s reads
# as two: m r theta'^2 is "m L theta'^2 + m s theta'^2".
PLANTED = {
    "dropped centripetal term": (
        "m * r * theta_rate**2 - k * s", "- k * s",
        "the derivation's equation s: add + m L theta'^2 + m s theta'^2 to its force side f"),
    "flipped Coriolis sign": (
        "-2 * m * r * s_rate * theta_rate", "2 * m * r * s_rate * theta_rate",
        "the derivation's equation theta: add - 4 m L theta' s' - 4 m s theta' s' to its force side f"),
    "sin for cos in gravity": (
        "m * g * np.cos(theta)])", "m * g * np.sin(theta)])",
        "the derivation's equation s: add - m g sin(theta) + m g cos(theta) to its force side f"),
    "Coriolis factor 2 lost": (
        "-2 * m * r * s_rate * theta_rate", "-m * r * s_rate * theta_rate",
        "the derivation's equation theta: add - m L theta' s' - m s theta' s' to its force side f"),
}


def write_case(cases_dir, equations):
    case = cases_dir / "elastic_pendulum"
    case.mkdir()
    (case / "scene.xml").write_text(SCENE)
    (case / "equations.py").write_text(equations)


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_the_derivation_runs_green(tmp_path):
    write_case(tmp_path, EQUATIONS)
    assert main(["run", "--cases", str(tmp_path)]) == 0


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
@pytest.mark.parametrize("old, new, named", PLANTED.values(), ids=PLANTED.keys())
def test_a_planted_error_is_named(tmp_path, capsys, old, new, named):
    assert EQUATIONS.count(old) == 1
    write_case(tmp_path, EQUATIONS.replace(old, new))
    assert main(["run", "--cases", str(tmp_path)]) == 1
    assert named in capsys.readouterr().out


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_without_energy_the_derivation_s_energy_rows_are_not_applicable(tmp_path, capsys):
    """energy() is optional: the derivation's energy rows say there is nothing to check, the engines'
    own energy rows stay, and a study that needs the derivation's energy is refused before any work."""
    without = EQUATIONS[:EQUATIONS.index("def energy")]
    write_case(tmp_path, without)
    assert main(["run", "--cases", str(tmp_path), "--json", str(tmp_path / "out.json")]) == 0
    assert "3 not applicable" in capsys.readouterr().out
    rows = [r for c in json.loads((tmp_path / "out.json").read_text())["cases"] for r in c["checks"]]
    energy = {(r["check"], r["quantity"], tuple(r["sources"])): r["status"] for r in rows if "energy" in r["quantity"]}
    assert energy[("energy", "energy drift", ("derivation",))] == "not applicable"
    assert energy[("pointwise", "energy", ("derivation", "mujoco"))] == "not applicable"
    assert energy[("energy", "energy drift", ("mujoco",))] == "pass"
    assert energy[("pointwise", "energy", ("mujoco", "pinocchio"))] == "pass"
    (tmp_path / "elastic_pendulum" / "case.toml").write_text(
        '[stability.energy_drift]\nwhy = "drift"\nmethods = ["RK4"]\nhorizon = 10.0\ndt = 0.01\nrtol = 1e-8\n'
        'output_step = 0.1\n')
    assert main(["report", "--cases", str(tmp_path), "--out", str(tmp_path / "pages")]) == 2
    assert "defines no energy(t, q, v, p); add it or remove the study" in capsys.readouterr().err
