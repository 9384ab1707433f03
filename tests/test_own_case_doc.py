"""docs/own-case.md, executed: its files written, its runs run, its outputs found in what dyncheck prints;
and `dyncheck new`, whose scaffold runs once its equations are written."""

import re
from pathlib import Path

import numpy as np
import pytest

from dyncheck.cli import main

GUIDE = Path(__file__).resolve().parent.parent / "docs" / "own-case.md"
BLOCK = re.compile(r"```(\w+)(?: (file=\S+|output))?\n(.*?)```", re.S)


def steps():
    """The guide's blocks that do something, in order: ("file", path, text), ("diff", path, text) and
    ("output", None, text)."""
    for language, what, text in BLOCK.findall(GUIDE.read_text()):
        if what == "output":
            yield "output", None, text.strip()
        elif what:
            yield ("diff" if language == "diff" else "file"), what.removeprefix("file="), text


@pytest.mark.full
def test_the_guide_runs_as_written(tmp_path, capsys):
    cases = tmp_path / "my_cases"
    expected_status = 0
    outputs = 0
    for kind, path, text in steps():
        if kind == "file":
            (cases / path).parent.mkdir(parents=True, exist_ok=True)
            (cases / path).write_text(text)
        elif kind == "diff":  # a change the reader makes: the "-" lines become the "+" lines
            old = "".join(line[1:] + "\n" for line in text.splitlines() if line.startswith("-"))
            new = "".join(line[1:] + "\n" for line in text.splitlines() if line.startswith("+"))
            source = (cases / path).read_text()
            assert old in source, f"the guide's change does not apply to {path}: {old!r}"
            (cases / path).write_text(source.replace(old, new, 1))
            expected_status = 1  # a planted error
        else:
            status = main(["run", "--cases", str(cases)])
            out = capsys.readouterr().out
            assert status == expected_status, out[-3000:]
            assert text in out, f"the guide's output {text!r} is not in the run's:\n{out[-3000:]}"
            outputs += 1
    assert outputs == 2


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_new_scaffolds_a_case_that_runs_once_written(tmp_path, capsys):
    scene = next(text for kind, path, text in steps() if kind == "file" and path.endswith("scene.xml"))
    (tmp_path / "scene.xml").write_text(scene)
    assert main(["new", "cart", "--scene", str(tmp_path / "scene.xml"), "--cases", str(tmp_path / "cases")]) == 0
    folder = tmp_path / "cases" / "cart"
    equations = (folder / "equations.py").read_text()
    assert "COORDS = ['x', 'theta']" in equations and '"m_bob": 0.3' in equations
    # Unwritten, it is refused before any work, naming what to write.
    assert main(["run", "--cases", str(tmp_path / "cases")]) == 2
    assert "NotImplementedError: mass_matrix: write M(q)" in capsys.readouterr().err
    # Written in the scaffold's own names, it passes.
    bodies = {"mass_matrix": 'M, m, l = p["m_cart"], p["m_bob"], p["bob_com_z"]\n'
                             "    return np.array([[M + m, m * l * np.cos(theta)], [m * l * np.cos(theta), m * l**2]])",
              "forces": 'm, l, k, g = p["m_bob"], p["bob_com_z"], p["k_x"], p["g"]\n'
                        "    return np.array([m * l * np.sin(theta) * theta_rate**2 - k * x, -m * g * l * np.sin(theta)])",
              "energy": 'M, m, l, k, g = p["m_cart"], p["m_bob"], p["bob_com_z"], p["k_x"], p["g"]\n'
                        "    return (0.5 * (M + m) * x_rate**2 + m * l * np.cos(theta) * x_rate * theta_rate\n"
                        "            + 0.5 * m * l**2 * theta_rate**2 + 0.5 * k * x**2 - m * g * l * np.cos(theta))"}
    for function, body in bodies.items():
        equations = re.sub(rf'(def {function}\(.*?)raise NotImplementedError\(".*?"\)', lambda m: m[1] + body,
                           equations, count=1, flags=re.S)
    (folder / "equations.py").write_text(equations)
    status = main(["run", "--cases", str(tmp_path / "cases")])
    captured = capsys.readouterr()
    assert status == 0, captured.out[-3000:] + captured.err


def test_new_refuses_an_existing_folder(tmp_path, capsys):
    (tmp_path / "cases" / "cart").mkdir(parents=True)
    (tmp_path / "scene.xml").write_text("<mujoco/>")
    assert main(["new", "cart", "--scene", str(tmp_path / "scene.xml"), "--cases", str(tmp_path / "cases")]) == 2
    assert "exists" in capsys.readouterr().err


REACTION = '''

def reactions(t, q, v, p):
    """The force of the cart on the bob along the rod (the bob's z axis), from Newton on the bob."""
    x, theta = q
    x_rate, theta_rate = v
    m, l, g = p["m"], p["l"], p["g"]
    x_acc, theta_acc = accelerations(t, q, v, p)
    fx = m * (x_acc + l * (np.cos(theta) * theta_acc - np.sin(theta) * theta_rate**2))
    fz = m * (l * (np.sin(theta) * theta_acc + np.cos(theta) * theta_rate**2) + g)
    return {"rod_z": -np.sin(theta) * fx + np.cos(theta) * fz}
'''


@pytest.mark.full
def test_a_wrong_reaction_is_named_while_the_equations_hold(tmp_path, capsys):
    """A reaction named after a force sensor of the scene (<sensor>_z) is compared with the engines'; with g
    dropped from it, the run names the term, and counts no consequences: the equations hold."""
    files = {path: text for kind, path, text in steps() if kind == "file"}
    folder = tmp_path / "cart_pendulum"
    folder.mkdir()
    (folder / "scene.xml").write_text(files["cart_pendulum/scene.xml"]
                                      .replace('diaginertia="1e-14 1e-14 1e-14"/>', 'diaginertia="1e-14 1e-14 1e-14"/>\n'
                                               '        <site name="pin"/>')
                                      .replace("</worldbody>", '</worldbody>\n  <sensor><force name="rod" site="pin"/></sensor>'))
    (folder / "equations.py").write_text(files["cart_pendulum/equations.py"] + REACTION)
    assert main(["run", "--cases", str(tmp_path)]) == 0, capsys.readouterr().out[-2000:]
    capsys.readouterr()
    (folder / "equations.py").write_text(files["cart_pendulum/equations.py"] + REACTION.replace(" + g)", ")"))
    assert main(["run", "--cases", str(tmp_path)]) == 1
    out = capsys.readouterr().out
    assert "the derivation's reaction rod_z: add + m g cos(theta) to it to agree with the engines" in out
    assert "consequences" not in out


def test_new_writes_the_dampers_drive_power_in_the_scaffold_s_names():
    """A scene with dampers: the scaffold's drive_power is written out (each damper takes c q'^2), in the names of
    its PARAMS, and its docstring opens with the case's name (not a body's)."""
    from dyncheck.case.scaffold import scaffold
    from engines.mjcf import describe
    equations, _ = scaffold("cartnew", describe(Path(__file__).parent.parent / "examples" / "forced_cart_pendulum" / "scene.xml"))
    assert equations.startswith('"""cartnew: ')
    namespace = {}
    exec(compile(equations, "equations.py", "exec"), namespace)
    p, v = namespace["PARAMS"], np.array([0.7, -2.0])
    assert namespace["drive_power"](0.0, np.zeros(2), v, p) == -(p["c_x"] * 0.7**2 + p["c_theta"] * 2.0**2)
