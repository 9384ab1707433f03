"""Closed kinematic loops through the harness (issue 14), on the slider-crank of examples/: the example runs green
against both engines (its crank's phi'', the loop's forces and the guide's normal force, the dependent joints);
a loop left open in a URDF twin is refused on load naming the loop; a derivation without the rod's inertia fails
its equation, and one whose position solve has a wrong sign fails that row."""

from functools import partial
from pathlib import Path

import pytest

import test_mechanisms
from test_mechanisms import run

pytestmark = pytest.mark.full  # runs of the cases' engines, seconds each: `pytest -m full`

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "slider_crank"
example = partial(test_mechanisms.example, source=EXAMPLE)

# The example's open tree for Pinocchio's URDF reader: the same bodies and joints, and no loop, which a URDF
# cannot write.
URDF = """<robot name="slider_crank">
  <link name="ground"/>
  <link name="crank"><inertial><origin xyz="0.05 0 0"/><mass value="1"/>
    <inertia ixx="1e-14" ixy="0" ixz="0" iyy="0.000833333333333333" iyz="0" izz="0.000833333333333333"/></inertial></link>
  <link name="rod"><inertial><origin xyz="0.15 0 0"/><mass value="0.5"/>
    <inertia ixx="1e-14" ixy="0" ixz="0" iyy="0.00375" iyz="0" izz="0.00375"/></inertial></link>
  <link name="slider"><inertial><mass value="0.8"/>
    <inertia ixx="1e-14" ixy="0" ixz="0" iyy="1e-14" iyz="0" izz="1e-14"/></inertial></link>
  <joint name="phi" type="continuous"><parent link="ground"/><child link="crank"/><axis xyz="0 -1 0"/></joint>
  <joint name="psi" type="revolute"><parent link="crank"/><child link="rod"/><origin xyz="0.1 0 0"/>
    <axis xyz="0 -1 0"/><limit lower="-1e300" upper="1e300" effort="0" velocity="0"/></joint>
  <joint name="x" type="prismatic"><parent link="ground"/><child link="slider"/><origin xyz="0.4 0 0"/>
    <axis xyz="1 0 0"/><limit lower="-1e300" upper="1e300" effort="0" velocity="0"/></joint>
</robot>
"""


def rows(out, quantity):
    """The printed rows of a quantity: their words."""
    return [line.split() for line in out.splitlines() if f" {quantity} " in line]


def test_the_slider_crank_passes_against_both_engines(tmp_path, capsys):
    status, out, _ = run(example(tmp_path), capsys)
    assert status == 0, out
    for quantity in ("phi_acc", "loop_x", "loop_z", "guide_z", "psi (dependent)", "x_rate (dependent)"):
        compared = [" ".join(words) for words in rows(out, quantity)]
        assert any("derivation vs mujoco" in line for line in compared), (quantity, out)
        assert any("derivation vs pinocchio" in line for line in compared), (quantity, out)
    assert "work-energy balance" in out


def test_a_loop_left_open_in_the_urdf_is_refused(tmp_path, capsys):
    status, _, err = run(example(tmp_path, urdf=URDF), capsys)
    assert status == 2
    assert "scene.urdf: no loop matches" in err and "equality 'loop'" in err, err


def test_a_derivation_without_the_rod_s_inertia_fails_its_equation(tmp_path, capsys):
    edits = [("equations.py", " + I2 * k**2 + p[\"m3\"]", " + p[\"m3\"]"),
             ("equations.py", " + I2 * k * k_phi + m3", " + m3")]
    status, out, _ = run(example(tmp_path, edits), capsys)
    assert status == 1
    equation = [words for words in rows(out, "residual") if words[-1] == "fail"]
    assert [words[1:3] for words in equation] == [["phi", "residual"]] * 2, out  # against both engines
    # located in the equation (the missing I2 k(phi)^2 is no candidate term); the other rows its consequences
    assert "the derivation's equation phi: no sum of up to 3 candidate terms" in out
    assert "other failing rows compare quantities computed from these equations: consequences" in out


def test_a_wrong_sign_in_the_position_solve_fails_its_row(tmp_path, capsys):
    status, out, _ = run(example(tmp_path, [("equations.py", '{"psi": theta - phi,', '{"psi": phi - theta,')]), capsys)
    assert status == 1
    failing = {(words[1], words[3], words[5]) for words in rows(out, "(dependent)")
               if words[0] == "pointwise" and words[-1] == "fail"}
    assert failing == {("psi", "derivation", "mujoco"), ("psi", "derivation", "pinocchio")}, out
