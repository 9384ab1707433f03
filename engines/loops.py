"""Closed kinematic loops in both engines: the scene's loop-closing constraints described alike and compared, the
position and velocity solve for the dependent joints, and the constrained accelerations and loop forces.

A loop is an MJCF <connect>: a point of body1 held on a point of body2.  MuJoCo models it as a soft constraint,
Pinocchio (its MJCF reader's "legacy" RigidConstraintModel, CONTACT_3D) as a rigid one.  Everything else that
MuJoCo's <equality> holds (weld, joint, tendon, flex) is refused on load: Pinocchio's MJCF reader drops joint and
tendon equalities without a word, and a weld's relative orientation is not compared here.

Forces are those on body1 at its anchor (the pin), world axes, N: in MuJoCo J^T f is the generalised force of
f on body1's anchor and -f on body2's (J = d(p1 - p2)/dq), in Pinocchio lambda_c is the force on joint1 in the
constraint's LOCAL frame at the anchor.
"""

import copy
import math
from dataclasses import dataclass, field

import mujoco
import numpy as np
import pinocchio as pin

STIFFEST = mujoco.mjMAXIMP  # 0.9999: MuJoCo clamps solimp's impedance to it
ANCHOR_ATOL = 1e-12
"""m.  Both readers take an anchor from the same decimal text; MuJoCo's compiler puts body2's anchor where body1's
is at qpos0, Pinocchio's reader at the neutral configuration, each composing a few placements: they differ by
rounding, a few eps of the scene's lengths (~1e-16 m for a metre-sized scene).  Any real difference is one of the
file's decimals, far above this."""
NEWTON_ITERATIONS = 30  # Newton converges quadratically from a stage's start; the rest are a stalled solve
STAGE = 0.2
"""The largest move of an independent joint (rad, or m over the scene's extent) between two closures of the
continuation: small enough for Newton to stay on the branch the scene is assembled on."""
CLOSED = 1e-12
"""A loop closed to rounding: the residual over the scene's extent after Newton has stopped improving (measured:
~1e-17 m on a 0.4 m scene); a loop that cannot close (a rod too short) stalls orders of magnitude above."""
PROXIMAL = dict(accuracy=1e-14, mu=1e-8, max_iter=50)
"""Pinocchio's constraintDynamics: mu > 0 regularises the KKT system, singular where a connect has a row with no
force direction (a planar loop's normal row), where mu = 0 gives NaN; its proximal iterations remove mu's bias
to `accuracy` (3-4 iterations here)."""


@dataclass(frozen=True)
class Loop:
    """A loop-closing point constraint as both engines read it: anchor1 of body1 held on anchor2 of body2, each in
    its body's frame (m).  A body is named after the moving body that carries it: a jointless body (MJCF's
    "ground") is folded into its parent, and a fixed one is "world".  The name is the MJCF element's, for messages
    (Pinocchio's reader keeps none), and is not compared."""
    kind: str
    body1: str
    body2: str
    anchor1: tuple
    anchor2: tuple
    name: str = field(default="", compare=False)

    def matches(self, other):
        return ((self.kind, self.body1, self.body2) == (other.kind, other.body1, other.body2)
                and np.allclose(self.anchor1, other.anchor1, rtol=0, atol=ANCHOR_ATOL)
                and np.allclose(self.anchor2, other.anchor2, rtol=0, atol=ANCHOR_ATOL))

    def __str__(self):
        points = lambda a: "(" + " ".join(f"{x:g}" for x in a) + ")"
        return f"<{self.kind}> of {self.body1} {points(self.anchor1)} to {self.body2} {points(self.anchor2)}"


def _point(array):
    return tuple(float(x) for x in array)


def refuse_unmatched(mujoco_loops, pinocchio_loops, mujoco_path, pinocchio_path):
    """ValueError for a loop that one scene file closes and the other does not (a URDF closes none)."""
    for loop in mujoco_loops:
        if not any(loop.matches(other) for other in pinocchio_loops):
            raise ValueError(f"{pinocchio_path}: no loop matches {mujoco_path}'s equality '{loop.name}', {loop}; "
                             "a loop left open in one engine would be locked or free there")
    for loop in pinocchio_loops:
        if not any(loop.matches(other) for other in mujoco_loops):
            raise ValueError(f"{mujoco_path}: no loop matches {pinocchio_path}'s {loop}")


def _refusal(path, owner, shown, why, fix):
    return ValueError(f"{path}: {owner} {shown} is not modelled by dyncheck ({why}); {fix}")


# -- MuJoCo ------------------------------------------------------------------------------------------------


class MujocoLoops:
    """The <connect> loops of a compiled MuJoCo model `m` read from `path`; refuses on construction what is not one."""

    def __init__(self, m, path):
        self.m, self.path = m, str(path)
        self._refuse_unsupported()
        self.loops = tuple(self._describe(e) for e in range(m.neq))
        self._scratch = mujoco.MjData(m)  # the solve's, so that a caller's data keeps its state

    def _refuse_unsupported(self):
        m, path = self.m, self.path
        for e in range(m.neq):
            kind = mujoco.mjtEq(m.eq_type[e]).name[5:].lower()
            owner = f"equality '{mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_EQUALITY, e) or e}'"
            if kind != "connect":
                raise _refusal(path, owner, f"<{kind}>", "only <connect> closes a loop here: Pinocchio's MJCF reader "
                               "drops joint and tendon equalities", "close the loop with a <connect>")
            if not m.eq_active0[e]:
                raise _refusal(path, owner, '<connect active="false">', "Pinocchio's MJCF reader closes it anyway",
                               "remove the constraint, or make it active")
            if np.any(m.eq_solimp[e][:2] < STIFFEST):
                shown = " ".join(f"{x:g}" for x in m.eq_solimp[e])
                raise _refusal(path, owner, f'<connect solimp="{shown}">', "softer than MuJoCo's stiffest, 0.9999, "
                               "its loop force is off by per cents", 'write solimp="0.9999 0.9999 0.001 0.5 2"')

    def _describe(self, e):
        m = self.m
        if m.eq_objtype[e] == mujoco.mjtObj.mjOBJ_SITE:  # site form: each anchor is a site's position
            sites = m.eq_obj1id[e], m.eq_obj2id[e]
            bodies, anchors = [m.site_bodyid[s] for s in sites], [m.site_pos[s] for s in sites]
        else:  # body form: anchor1 in body1, anchor2 computed by the compiler at qpos0
            bodies, anchors = [m.eq_obj1id[e], m.eq_obj2id[e]], [m.eq_data[e][0:3], m.eq_data[e][3:6]]
        (body1, anchor1), (body2, anchor2) = (self._on_moving_body(b, a) for b, a in zip(bodies, anchors))
        return Loop("connect", body1, body2, anchor1, anchor2, mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_EQUALITY, e))

    def _on_moving_body(self, body, point):
        """(name, point in its frame) of the nearest body at or above `body` that a joint moves, else the world."""
        m, point = self.m, np.array(point, dtype=float)
        while body and not m.body_jntnum[body]:
            rotated = np.empty(3)
            mujoco.mju_rotVecQuat(rotated, point, m.body_quat[body])
            point, body = m.body_pos[body] + rotated, m.body_parentid[body]
        return ("world" if body == 0 else mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, body)), _point(point)

    def _joint(self, name):
        j = mujoco.mj_name2id(self.m, mujoco.mjtObj.mjOBJ_JOINT, name)
        if j < 0:
            raise ValueError(f"{self.path}: no joint named '{name}'")
        return int(self.m.jnt_qposadr[j]), int(self.m.jnt_dofadr[j])

    def _constraint(self, qpos):
        """The loops' residual p1 - p2 (world, m) and its Jacobian d/dq (rows x nv) at qpos: MuJoCo's equality rows
        of efc_pos and efc_J (the only rows: the adapter refuses limits, contacts and friction)."""
        m, d = self.m, self._scratch
        d.qpos[:] = qpos
        mujoco.mj_fwdPosition(m, d)
        return d.efc_pos[:d.nefc].copy(), _jacobian(m, d)

    def _integrate(self, qpos, step):
        qpos = qpos.copy()
        mujoco.mj_integratePos(self.m, qpos, step, 1.0)
        return qpos

    def close(self, positions, rates, start=None):
        """qpos and qvel of the whole scene with the independent joints at `positions` and `rates` ({joint: value},
        hinges and slides) and the dependent ones closing every loop, on the branch of `start` (default qpos0,
        the scene's assembly)."""
        addresses = {name: self._joint(name) for name in positions}
        independent = np.array([dof for _, dof in addresses.values()], dtype=int)
        target = np.array([positions[name] for name in addresses])
        begin = self.m.qpos0 if start is None else start
        slides = [self.m.jnt_type[mujoco.mj_name2id(self.m, mujoco.mjtObj.mjOBJ_JOINT, name)] == mujoco.mjtJoint.mjJNT_SLIDE
                  for name in addresses]
        qpos, jacobian = _continuation(np.array(begin, dtype=float), [qadr for qadr, _ in addresses.values()], target,
                                       slides, independent, self.m.nv, self._constraint, self._integrate,
                                       self.m.stat.extent, self.path)
        qvel = _dependent_rates(jacobian, independent, np.array([rates[name] for name in addresses]))
        return qpos, qvel

    def constrained(self, d):
        """MuJoCo's constrained accelerations (nv,) and each loop's force on body1 at its anchor, world, (nloops, 3),
        with the softness removed, from the data `d` of mj_forward at a state on the loops.

        MuJoCo's constraint rows obey J qacc = aref - R f, its soft model (R > 0: solimp, solref); aref = -Jdot v
        - b J v - k r holds the loop's Jdot v and a drift correction that vanishes on the loops (r, J v at the
        solve's rounding: ~1e-13 m/s^2 with b = 100 /s, k = 2500 /s^2).  With R = 0, Gauss's principle on MuJoCo's
        own M, bias and J gives A f = aref - J qacc_smooth, A = J M^-1 J^T, and qacc = qacc_smooth + M^-1 J^T f:
        the rigid answer, independent of the solver's convergence (its tolerance, 1e-8, shows in efc_force at
        ~1e-11).  Its error is rounding times the condition of A on its rows with a force direction (a planar
        loop's normal row is identically 0, and so is its force); measured against the derivation: 2e-15 of phi'', 8e-15
        of the loop force."""
        qacc, force = self._rigid(d)
        return qacc, _per_loop(force, d.efc_id[:d.nefc], self.m.neq)

    def _rigid(self, d):
        """`constrained`'s accelerations and its force of every constraint row."""
        jacobian = _jacobian(self.m, d)
        inverse_mass_jt = np.empty(jacobian.shape)
        mujoco.mj_solveM(self.m, d, inverse_mass_jt, jacobian)  # rows: (M^-1 J^T)^T
        inverse_mass_jt = inverse_mass_jt.T
        live = np.any(jacobian != 0, axis=1)
        force = np.zeros(d.nefc)
        A = (jacobian @ inverse_mass_jt)[np.ix_(live, live)]
        force[live] = np.linalg.solve(A, (d.efc_aref[:d.nefc] - jacobian @ d.qacc_smooth)[live])
        return d.qacc_smooth + inverse_mass_jt @ force, force

    def impose(self, d):
        """Put `constrained`'s rigid answer into the data `d` of mj_forward (qacc, efc_force, qfrc_constraint), so
        that what MuJoCo computes from them next (mj_rnePostConstraint, its acceleration-stage sensors) reads the
        rigid loop; each loop's force on body1 at its anchor, world, (nloops, 3)."""
        qacc, force = self._rigid(d)
        d.qacc[:], d.efc_force[:d.nefc] = qacc, force
        d.qfrc_constraint[:] = _jacobian(self.m, d).T @ force
        return _per_loop(force, d.efc_id[:d.nefc], self.m.neq)

    def rates(self, d, independent):
        """Every dof's rate per unit rate of each independent dof (nv x len(independent)) at the state of `d`
        (after mj_fwdPosition): the velocity solve's linear map, J v = 0."""
        return _rates_map(_jacobian(self.m, d), independent)

    def freedom(self):
        """The scene's degrees of freedom at its assembly (qpos0): nv less the rank of the loops' Jacobian."""
        jacobian = self._constraint(self.m.qpos0)[1]
        return self.m.nv - np.linalg.matrix_rank(jacobian)

    def softness_doubled(self):
        """A copy of the model with every loop's softness 1 - solimp doubled (the impedance 0.9999 becomes 0.9998):
        the soft force is f = (A + R)^-1 A f_rigid with R ~ (1 - solimp) / solimp, so what MuJoCo's own soft
        stepping departs from the rigid motion, first order in R, is the change of a run under this copy."""
        twin = copy.copy(self.m)  # a copy of the compiled model's arrays
        twin.eq_solimp[:, :2] = 1 - 2 * (1 - self.m.eq_solimp[:, :2])
        return twin


def _jacobian(m, d):
    """MuJoCo's constraint Jacobian efc_J, dense (nefc x nv)."""
    if not mujoco.mj_isSparse(m):
        return d.efc_J[:d.nefc * m.nv].reshape(d.nefc, m.nv).copy()
    dense = np.zeros((d.nefc, m.nv))
    mujoco.mju_sparse2dense(dense, d.efc_J, d.efc_J_rownnz, d.efc_J_rowadr, d.efc_J_colind)
    return dense


def _per_loop(force, loop_of_row, nloops):
    """Each loop's three rows of a force vector: (nloops, 3)."""
    return np.array([force[loop_of_row == e] for e in range(nloops)]).reshape(nloops, 3)


# -- Pinocchio ---------------------------------------------------------------------------------------------


class PinocchioLoops:
    """The loops of a Pinocchio model and its RigidConstraintModels (buildModelAndLegacyConstraintsFromMJCF's; a
    URDF's model has none) read from `path`; refuses on construction what is not a point constraint.  Build it
    after the model is complete (gravity, inertias): it makes its own data."""

    def __init__(self, model, constraints, path):
        self.model, self.path = model, str(path)
        self.constraints = pin.StdVec_RigidConstraintModel()
        for c in constraints:
            if c.type != pin.ContactType.CONTACT_3D:
                raise _refusal(path, f"constraint between joints '{model.names[c.joint1_id]}' and "
                               f"'{model.names[c.joint2_id]}'", f"({c.type.name})", "only <connect> closes a loop "
                               "here", "close the loop with a <connect>")
            self.constraints.append(c)
        self.loops = tuple(Loop("connect", self._body(c.joint1_id), self._body(c.joint2_id),
                                _point(c.joint1_placement.translation), _point(c.joint2_placement.translation), c.name)
                           for c in self.constraints)
        self.data = model.createData()
        self.datas = pin.StdVec_RigidConstraintData()
        for c in self.constraints:
            self.datas.append(c.createData())
        pin.initConstraintDynamics(model, self.data, self.constraints, self.datas)
        self.settings = pin.ProximalSettings(PROXIMAL["accuracy"], PROXIMAL["mu"], PROXIMAL["max_iter"])

    def _body(self, joint):
        """The body a joint moves, named as MuJoCo names it (the MJCF body frame that hangs on the joint), or the
        world.  A joint's frame is its body's: dyncheck refuses an MJCF joint pos."""
        if joint == 0:
            return "world"
        return next(f.name for f in self.model.frames if f.type == pin.FrameType.BODY and f.parentJoint == joint)

    def _joint(self, name):
        if not self.model.existJointName(name):
            raise ValueError(f"{self.path}: no joint named '{name}'")
        return self.model.joints[self.model.getJointId(name)]

    def _constraint(self, q):
        """The loops' residual p1 - p2 (world, m) and its Jacobian d/dq, from Pinocchio's constraint placements and
        getConstraintJacobian (in each constraint's LOCAL frame: turned to the world)."""
        model, data = self.model, self.data
        pin.computeJointJacobians(model, data, q)
        residuals, jacobians = [], []
        for c, cd in zip(self.constraints, self.datas):
            c.calc(model, data, cd)
            residuals.append(cd.oMc1.translation - cd.oMc2.translation)
            jacobians.append(cd.oMc1.rotation @ pin.getConstraintJacobian(model, data, c, cd)[:3])
        return np.concatenate(residuals), np.vstack(jacobians)

    def _integrate(self, q, step):
        return pin.integrate(self.model, q, step)

    def close(self, positions, rates, start=None):
        """q and v of the whole scene (as MujocoLoops.close), on the branch of `start` (default the neutral
        configuration, where the MJCF scene is assembled)."""
        joints = {name: self._joint(name) for name in positions}
        independent = np.array([joint.idx_v for joint in joints.values()], dtype=int)
        target = np.array([positions[name] for name in joints])
        slides = ["Prismatic" in joint.shortname() for joint in joints.values()]
        begin = pin.neutral(self.model) if start is None else np.array(start, dtype=float)
        extent = max(np.linalg.norm(p.translation) for p in self.model.jointPlacements)
        q, jacobian = _continuation(begin, [joint.idx_q for joint in joints.values()], target, slides, independent,
                                    self.model.nv, self._constraint, self._integrate, extent, self.path)
        v = _dependent_rates(jacobian, independent, np.array([rates[name] for name in joints]))
        return q, v

    def rates(self, q, independent):
        """Every dof's rate per unit rate of each independent dof (nv x len(independent)) at q, on the loops."""
        return _rates_map(self._constraint(q)[1], independent)

    def constrained(self, q, v, tau):
        """Pinocchio's constrained accelerations (nv,) under the generalised forces tau, and each loop's force on
        body1 at its anchor, world, (nloops, 3): constraintDynamics, Baumgarte gains 0 (the state is on the loops)."""
        ddq = pin.constraintDynamics(self.model, self.data, q, v, tau, self.constraints, self.datas, self.settings)
        forces = self.data.lambda_c.reshape(-1, 3)
        return ddq.copy(), np.array([cd.oMc1.rotation @ f for cd, f in zip(self.datas, forces)])


# -- the solve, for either engine ----------------------------------------------------------------------------


def _continuation(q, addresses, target, slides, independent, nv, constraint, integrate, extent, path):
    """The configuration with the independent joints (configuration `addresses`, dofs `independent`, `slides` the
    slides among them) at `target` and every loop closed, and the loops' Jacobian there: reached from q in stages of
    at most STAGE (rad, a slide's m over the scene's extent) by the dependent joints, each closed by Newton, so
    that it stays on the branch q is on.  Every joint not independent is dependent."""
    dependent = np.setdiff1d(np.arange(nv), independent)
    scale = np.where(slides, extent, 1.0)
    start = q[addresses].copy()
    stages = max(1, math.ceil(np.max(np.abs(target - start) / scale, initial=0.0) / STAGE))
    for stage in range(1, stages + 1):
        q = q.copy()
        q[addresses] = start + (target - start) * stage / stages
        q = _newton(q, dependent, nv, constraint, integrate)
    residual, jacobian = constraint(q)
    gap = np.max(np.abs(residual), initial=0.0)
    if not gap <= CLOSED * extent:
        raise ValueError(f"{path}: the loops do not close with the independent joints at {target.tolist()}: "
                         f"{gap:.3g} m apart")
    return q, jacobian


def _newton(q, dependent, nv, constraint, integrate):
    """q with the dependent dofs moved by Newton steps (least squares: a planar loop's normal row is 0) until the
    residual stops shrinking: closed to rounding."""
    best = np.inf
    for _ in range(NEWTON_ITERATIONS):
        residual, jacobian = constraint(q)
        size = np.max(np.abs(residual), initial=0.0)
        if not size < best / 2:
            break
        best = size
        step = np.zeros(nv)
        step[dependent] = -np.linalg.lstsq(jacobian[:, dependent], residual, rcond=None)[0]
        q = integrate(q, step)
    return q


def _rates_map(jacobian, independent):
    """The velocity solve as a matrix: every dof's rate per unit rate of each independent dof."""
    return np.column_stack([_dependent_rates(jacobian, np.asarray(independent), unit)
                            for unit in np.eye(len(independent))])


def _dependent_rates(jacobian, independent, rates):
    """Every dof's rate: the independent ones given, the dependent ones with J v = 0."""
    nv = jacobian.shape[1]
    dependent = np.setdiff1d(np.arange(nv), independent)
    v = np.zeros(nv)
    v[independent] = rates
    v[dependent] = -np.linalg.lstsq(jacobian[:, dependent], jacobian[:, independent] @ rates, rcond=None)[0]
    return v
