"""The MJCF's <connect> loops on Drake's model (engines.drake_adapter), which Drake's continuous plant refuses:
closed and solved here on Drake's kinematics, as engines.loops closes and solves them on MuJoCo's and Pinocchio's."""

import numpy as np
from pydrake.multibody.tree import JacobianWrtVariable, PrismaticJoint

from engines.drake_scene import Refused
from engines.loops import Loop, _continuation, _dependent_rates, _rates_map


class DrakeLoops:
    """The MJCF's <connect> loops on a Drake model (removed from Drake's plant, which refuses them in continuous
    time): each a point of body1 held on a point of body2, as engines.loops.Loop; closed by engines.loops'
    continuation on Drake's kinematics, and solved rigidly by Gauss's principle on Drake's M, bias and point
    Jacobians, as MujocoLoops does on MuJoCo's."""

    def __init__(self, model, document):
        self.model, self.plant, self.context = model, model.plant, model.context
        elements = [] if document is None else [e for equality in document.iter("equality") for e in equality]
        for element in elements:
            if element.tag != "connect":
                raise Refused(f"{model.path}: <{element.tag}>: only <connect> closes a loop here")
            if element.get("site1") is not None:
                raise Refused(f"{model.path}: <connect site1=...>: Drake's parser ignores sites; only the body form "
                              "(body1, body2, anchor) is read by this adapter")
        self.names = [e.get("name", "") for e in elements]
        self._points = [self._describe(e) for e in elements]  # (body1, anchor1, body2, anchor2)
        self.loops = tuple(Loop("connect", b1.name(), b2.name(), tuple(a1), tuple(a2), name)
                           for (b1, a1, b2, a2), name in zip(self._points, self.names))

    def _describe(self, element):
        """body1, its anchor, body2 and its anchor: where body1's is at the default configuration (MuJoCo's
        compiler puts body2's anchor at qpos0, which is Drake's zero)."""
        body1, body2 = (self.model._body(element.get(b)) for b in ("body1", "body2"))
        anchor1 = np.array([float(x) for x in element.get("anchor", "0 0 0").split()])
        self.plant.SetPositions(self.context, np.zeros(self.model.nq))
        world = body1.EvalPoseInWorld(self.context) @ anchor1
        return body1, anchor1, body2, body2.EvalPoseInWorld(self.context).inverse() @ world

    def _constraint(self, positions):
        """The loops' residual p1 - p2 (world, m) and its Jacobian d/dq at `positions` (hinges and slides: q = v)."""
        self.plant.SetPositions(self.context, positions)
        residuals, jacobians = [], []
        for body1, anchor1, body2, anchor2 in self._points:
            ends = [(self.plant.CalcPointsPositions(self.context, b.body_frame(), a, self.plant.world_frame())[:, 0],
                     self.plant.CalcJacobianTranslationalVelocity(self.context, JacobianWrtVariable.kV, b.body_frame(),
                                                                  a, self.plant.world_frame(), self.plant.world_frame()))
                    for b, a in ((body1, anchor1), (body2, anchor2))]
            residuals.append(ends[0][0] - ends[1][0])
            jacobians.append(ends[0][1] - ends[1][1])
        return np.concatenate(residuals), np.vstack(jacobians)

    def close(self, positions, rates, start=None):
        """Drake's positions and velocities with the independent joints at `positions`, `rates` ({joint: value})
        and the dependent ones closing every loop, on the branch of `start` (default the assembly, Drake's zero)."""
        joints = [self.model._joint(name) for name in positions]
        independent = np.array([joint.velocity_start() for joint in joints], dtype=int)
        begin = np.zeros(self.model.nq) if start is None else np.array(start, dtype=float)
        extent = max(np.linalg.norm(self.plant.get_joint(j).frame_on_parent().CalcPoseInBodyFrame(
            self.context).translation()) for j in self.plant.GetJointIndices())
        slides = [isinstance(joint, PrismaticJoint) for joint in joints]
        q, jacobian = _continuation(begin, [joint.position_start() for joint in joints],
                                    np.array(list(positions.values())), slides, independent, self.model.nv,
                                    self._constraint, lambda q, step: q + step, extent, self.model.path)
        self.plant.SetPositions(self.context, q)
        return q, _dependent_rates(jacobian, independent, np.array(list(rates.values())))

    def rates(self, independent):
        """Every dof's rate per unit rate of each independent dof, at the context's (closed) positions."""
        return _rates_map(self._constraint(self.plant.GetPositions(self.context))[1], independent)

    def constrained(self, mass, force):
        """The rigid loop's accelerations and each loop's force on body1 at its anchor (world, (nloops, 3)) at the
        context's state: M acc = force + J^T f, J acc = -Jdot v, `force` the generalised forces less the bias.
        Rows that carry no force direction (a planar loop's normal) are left out of the solve (as MujocoLoops)."""
        jacobian = self._constraint(self.plant.GetPositions(self.context))[1]
        bias = np.concatenate([self._bias(b1, a1) - self._bias(b2, a2) for b1, a1, b2, a2 in self._points])
        free = np.linalg.solve(mass, force)
        inverse_mass_jt = np.linalg.solve(mass, jacobian.T)
        live = np.any(jacobian != 0, axis=1)
        loop_force = np.zeros(len(jacobian))
        loop_force[live] = np.linalg.solve((jacobian @ inverse_mass_jt)[np.ix_(live, live)],
                                           (-bias - jacobian @ free)[live])
        self._jacobian = jacobian
        return free + inverse_mass_jt @ loop_force, loop_force.reshape(-1, 3)

    def _bias(self, body, anchor):
        return self.plant.CalcBiasTranslationalAcceleration(self.context, JacobianWrtVariable.kV, body.body_frame(),
                                                            anchor, self.plant.world_frame(),
                                                            self.plant.world_frame())[:, 0]

    def generalised(self, loop_forces):
        """J^T f: the loops' forces as generalised forces (at the last `constrained` state)."""
        return self._jacobian.T @ loop_forces.reshape(-1)

    def applied(self, loop_forces):
        """(world point, body index, force) of each loop's force on body1 at its anchor and the opposite on body2,
        at the context's positions; none without loops."""
        if loop_forces is None:
            return []
        out = []
        for (body1, anchor1, body2, anchor2), force in zip(self._points, loop_forces):
            for body, anchor, sign in ((body1, anchor1, 1.0), (body2, anchor2, -1.0)):
                out.append((body.EvalPoseInWorld(self.context) @ anchor, int(body.index()), sign * force))
        return out
