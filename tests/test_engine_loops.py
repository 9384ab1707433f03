"""engines/loops.py on the slider-crank (examples/slider_crank):
each engine's position and velocity solve and its constrained dynamics against the derivation, MuJoCo's softness
measured and bounded, a loop one side lacks and an equality that is not a <connect> refused."""

import copy
import importlib.util
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import solve_ivp

from engines.loops import STIFFEST, MujocoLoops, PinocchioLoops, refuse_unmatched
from test_loops import URDF  # the example's open tree, the same the harness's test refuses

FOLDER = Path(__file__).resolve().parent.parent / "examples" / "slider_crank"
SCENE = FOLDER / "scene.xml"
CONNECT = '<connect name="loop" body1="rod" body2="slider" anchor="0.3 0 0" solimp="0.9999 0.9999 0.001 0.5 2"/>'
AGREE = 1e-12
"""Relative to each quantity's largest size over the states.  Both sides are exact for the same rigid loop: the
derivation in closed form, Pinocchio's constraintDynamics and MuJoCo's hardened equations each a few solves of
3 x 3 systems whose condition is ~1e2 (the mass ratios and r / l), on a state closed to ~1e-16 m.  Measured over
20 states: MuJoCo 1.9e-15 on phi'', 8e-15 on the forces; Pinocchio 6e-16 and 1.1e-15.  1e-12 leaves three orders for other platforms; a
dropped term (the Jdot v of MuJoCo's aref, the softness) shows at 1e-5 or above."""
SOLVED = 1e-13
"""rad, m, and per second.  The solve closes to rounding (~1e-16 m); the rates follow through the loop's
Jacobian, with factors up to the rates (15 rad/s): measured 4e-16 in position, 1.4e-14 in rate."""


def _derivation():
    spec = importlib.util.spec_from_file_location("slider_crank_equations", FOLDER / "equations.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


EQ = _derivation()
P = EQ.PARAMS
TORQUE = np.array([P["tau"], 0.0, 0.0])  # the crank's, on phi (qpos order phi, psi, x in both engines)


def _states(n=20, seed=1):
    """(phi, phi') on the loop: the crank anywhere, up to 15 rad/s either way."""
    rng = np.random.default_rng(seed)
    return np.c_[rng.uniform(-np.pi, np.pi, n), rng.uniform(-15, 15, n)]


@pytest.fixture(scope="module")
def engines():
    m = mujoco.MjModel.from_xml_path(str(SCENE))
    model, constraints = pin.buildModelAndLegacyConstraintsFromMJCF(str(SCENE))
    return m, MujocoLoops(m, SCENE), PinocchioLoops(model, constraints, SCENE)


@pytest.fixture(scope="module")
def evaluations(engines):
    """At each state: the derivation's (phi'', loop_x, loop_z), and per engine its solve and the same three."""
    m, mj, pn = engines
    d = mujoco.MjData(m)
    rows = []
    for phi, rate in _states():
        positions, rates = EQ.dependent([phi], [rate], P)
        expected_q = np.array([phi, positions["psi"], positions["x"]])
        expected_v = np.array([rate, rates["psi"], rates["x"]])
        reactions = EQ.reactions(0.0, [phi], [rate], P)
        derivation = [EQ.accelerations(0.0, [phi], [rate], P)[0], reactions["loop_x"], reactions["loop_z"]]
        d.qpos[:], d.qvel[:] = mj.close({"phi": phi}, {"phi": rate})
        solved_mj = np.r_[d.qpos - expected_q, d.qvel - expected_v]
        d.qfrc_applied[:] = TORQUE
        mujoco.mj_forward(m, d)
        qacc, force = mj.constrained(d)
        q, v = pn.close({"phi": phi}, {"phi": rate})
        ddq, pin_force = pn.constrained(q, v, TORQUE)
        rows.append(dict(derivation=derivation, mujoco=[qacc[0], *force[0][[0, 2]]],
                         pinocchio=[ddq[0], *pin_force[0][[0, 2]]], soft=[d.qacc[0], *d.efc_force[[0, 2]]],
                         solved_mujoco=solved_mj, solved_pinocchio=np.r_[q - expected_q, v - expected_v]))
    return {key: np.array([row[key] for row in rows]) for key in rows[0]}


def _relative(evaluations, source):
    """Worst error of phi'', loop_x, loop_z over the states, each over its largest size."""
    derivation = evaluations["derivation"]
    return np.max(np.abs(evaluations[source] - derivation), axis=0) / np.max(np.abs(derivation), axis=0)


@pytest.mark.parametrize("source", ["mujoco", "pinocchio"])
def test_the_engines_constrained_dynamics_agree_with_the_derivation(evaluations, source):
    assert np.all(_relative(evaluations, source) < AGREE), _relative(evaluations, source)


@pytest.mark.parametrize("engine", ["mujoco", "pinocchio"])
def test_each_engines_solve_reproduces_the_derivations_dependent_joints(evaluations, engine):
    assert np.max(np.abs(evaluations["solved_" + engine])) < SOLVED


def test_the_solve_stays_on_the_branch_it_starts_from(engines):
    """From the assembly (rod along +x), the crank's half turn keeps the rod pointing to +x (cos theta > 0); from a
    start on the mirror branch (the slider on -x), the same crank angle closes there."""
    m, mj, _ = engines
    qpos, _ = mj.close({"phi": 3.0}, {"phi": 0.0})
    assert np.cos(qpos[0] + qpos[1]) > 0
    mirror = np.array([0.0, np.pi, -2 * P["l"]])  # crank along +x, the rod back along -x: the slider at r - l
    qpos, _ = mj.close({"phi": 0.5}, {"phi": 0.0}, start=mirror)
    assert np.cos(qpos[0] + qpos[1]) < 0


def test_a_loop_that_cannot_close_is_refused(tmp_path):
    """A crank longer than the rod reaches past the guide: the solve says how far apart the loop stays."""
    path = tmp_path / "long_crank.xml"
    path.write_text(SCENE.read_text().replace('body name="rod" pos="0.1 0 0"', 'body name="rod" pos="0.5 0 0"')
                    .replace('body name="slider" pos="0.4 0 0"', 'body name="slider" pos="0.8 0 0"'))
    with pytest.raises(ValueError, match="do not close"):
        MujocoLoops(mujoco.MjModel.from_xml_path(str(path)), path).close({"phi": 1.5}, {"phi": 0.0})


def test_mujocos_softness_is_measured_and_bounded(engines, evaluations):
    """Pointwise, MuJoCo's own (soft) answer departs from its hardened one by f - f_rigid = -(A + R)^-1 R f_rigid,
    so by at most max(R) / min eig(A) of the force: (1 - 0.9999) / 0.9999 times the ratio of MuJoCo's qpos0
    estimate of A's diagonal (which R is proportional to) to A's least eigenvalue, measured <= 1.4 here.  Measured:
    3.5e-5 of phi'', 1.1e-4 and 7.3e-5 of loop_x and loop_z, each over its largest size."""
    m, mj, _ = engines
    soft = _relative(evaluations, "soft")
    assert 1e-6 < soft[0] < 1e-4, soft
    assert np.all(soft[1:] < 2e-4), soft
    d = mujoco.MjData(m)
    for phi, rate in _states(5):
        d.qpos[:], d.qvel[:] = mj.close({"phi": phi}, {"phi": rate})
        d.qfrc_applied[:] = TORQUE
        mujoco.mj_forward(m, d)
        rigid = mj.constrained(d)[1][0]
        mass = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, mass)
        jacobian = d.efc_J[:d.nefc * m.nv].reshape(d.nefc, m.nv)[[0, 2]]  # the y row is 0: no force, no softness
        least = np.linalg.eigvalsh(jacobian @ np.linalg.solve(mass, jacobian.T)).min()
        bound = d.efc_R[:d.nefc].max() / least
        assert bound < 2 * (1 - STIFFEST)
        assert np.linalg.norm(d.efc_force[:3] - rigid) <= bound * np.linalg.norm(rigid)


def test_doubling_the_softness_measures_what_mujocos_stepping_departs_from_the_rigid_motion(engines):
    """0.2 s of MuJoCo's own RK4 (soft loop, solref's drift correction) from rest at the assembly, against the
    derivation integrated tightly: the crank's error is the softness's (RK4 at 1e-4 s adds ~1e-12 rad), first order
    in it, so the run with the softness doubled differs from the first by that error.  Measured: 2.3e-5 rad of
    3.1 rad travelled (RK4's own error 2.4e-12 rad), predicted to 4e-5 of itself."""
    m, mj, _ = engines
    seconds, step = 0.2, 1e-4

    def crank_angles(model):
        model.opt.timestep, model.opt.integrator = step, mujoco.mjtIntegrator.mjINT_RK4
        d = mujoco.MjData(model)
        d.qpos[:], d.qvel[:] = mj.close({"phi": 0.0}, {"phi": 0.0})
        d.qfrc_applied[:] = TORQUE
        angles = [d.qpos[0]]
        for _ in range(int(round(seconds / step))):
            mujoco.mj_step(model, d)
            angles.append(d.qpos[0])
        return np.array(angles)

    soft = crank_angles(copy.copy(m))
    doubled = crank_angles(mj.softness_doubled())
    times = np.arange(len(soft)) * step
    rigid = solve_ivp(lambda t, y: [y[1], EQ.accelerations(t, y[:1], y[1:], P)[0]], (0.0, seconds), [0.0, 0.0],
                      method="DOP853", t_eval=times, rtol=1e-12, atol=1e-12).y[0]
    error, estimate = soft - rigid, doubled - soft
    assert 1e-6 < np.max(np.abs(error)) < 1e-3 * np.ptp(rigid)
    assert np.max(np.abs(error - estimate)) < 0.01 * np.max(np.abs(error))  # second order: ~1e-4 of it


# -- loops that one side lacks, and equalities that are not loops ----------------------------------------------

def _variant(tmp_path, old, new):
    path = tmp_path / "scene.xml"
    path.write_text(SCENE.read_text().replace(old, new))
    return path


def test_both_engines_describe_the_loop_alike(engines):
    _, mj, pn = engines
    assert [(loop.body1, loop.body2) for loop in mj.loops] == [("rod", "slider")]
    assert mj.loops[0].matches(pn.loops[0])
    refuse_unmatched(mj.loops, pn.loops, SCENE, SCENE)


def test_the_site_form_of_connect_is_the_same_loop(engines, tmp_path):
    path = _variant(tmp_path, CONNECT, '<connect name="loop" site1="rod_end" site2="slider_pin" '
                                       'solimp="0.9999 0.9999 0.001 0.5 2"/>')
    path.write_text(path.read_text().replace('<joint name="psi" type="hinge" axis="0 -1 0"/>',
                                             '<joint name="psi" type="hinge" axis="0 -1 0"/><site name="rod_end" pos="0.3 0 0"/>')
                    .replace('<joint name="x" type="slide" axis="1 0 0"/>',
                             '<joint name="x" type="slide" axis="1 0 0"/><site name="slider_pin"/>'))
    sites = MujocoLoops(mujoco.MjModel.from_xml_path(str(path)), path).loops
    assert sites[0].matches(engines[1].loops[0])
    assert sites[0].matches(PinocchioLoops(*pin.buildModelAndLegacyConstraintsFromMJCF(str(path)), path).loops[0])


def test_a_loop_left_open_in_the_urdf_is_refused(engines, tmp_path):
    """Pinocchio from a URDF has no constraint model: the MJCF's loop has no match, and the message names it."""
    path = tmp_path / "scene.urdf"
    path.write_text(URDF)
    urdf = PinocchioLoops(pin.buildModelFromUrdf(str(path)), [], path)
    with pytest.raises(ValueError, match=r"scene.urdf: no loop matches .*equality 'loop', <connect> of rod"):
        refuse_unmatched(engines[1].loops, urdf.loops, SCENE, path)


def test_a_loop_left_open_in_the_mjcf_is_refused(engines, tmp_path):
    path = _variant(tmp_path, CONNECT, "")
    open_scene = MujocoLoops(mujoco.MjModel.from_xml_path(str(path)), path)
    with pytest.raises(ValueError, match="no loop matches"):
        refuse_unmatched(open_scene.loops, engines[2].loops, path, SCENE)


def test_a_loop_closed_at_another_point_is_refused(engines, tmp_path):
    path = _variant(tmp_path, 'anchor="0.3 0 0"', 'anchor="0.25 0 0"')
    moved = MujocoLoops(mujoco.MjModel.from_xml_path(str(path)), path)
    with pytest.raises(ValueError, match=r"\(0.25 0 0\)"):
        refuse_unmatched(moved.loops, engines[2].loops, path, SCENE)


@pytest.mark.parametrize("equality, shown", [
    ('<weld name="clamp" body1="rod" body2="slider"/>', "equality 'clamp' <weld>"),
    ('<joint name="gear" joint1="phi" joint2="psi"/>', "equality 'gear' <joint>"),
    ('<tendon name="coupling" tendon1="crank_turns"/>', "equality 'coupling' <tendon>"),
    (CONNECT.replace("/>", ' active="false"/>'), "equality 'loop' <connect active=\"false\">"),
    (CONNECT.replace("0.9999 0.9999", "0.9 0.95"), "equality 'loop' <connect solimp=\"0.9 0.95 0.001 0.5 2\">"),
])
def test_an_unsupported_equality_is_refused_by_name(tmp_path, equality, shown):
    path = _variant(tmp_path, CONNECT, equality)
    path.write_text(path.read_text().replace(
        "<equality>", '<tendon><fixed name="crank_turns"><joint joint="phi" coef="1"/></fixed></tendon><equality>'))
    with pytest.raises(ValueError, match=f"scene.xml: {shown} is not modelled by dyncheck"):
        MujocoLoops(mujoco.MjModel.from_xml_path(str(path)), path)


def test_a_weld_read_by_pinocchio_is_refused(tmp_path):
    path = _variant(tmp_path, CONNECT, '<weld name="clamp" body1="rod" body2="slider"/>')
    with pytest.raises(ValueError, match=r"joints 'psi' and 'x' \(CONTACT_6D\) is not modelled"):
        PinocchioLoops(*pin.buildModelAndLegacyConstraintsFromMJCF(str(path)), path)
