"""What an MJCF scene holds, read once by MuJoCo's compiler: its joints, its force and torque sensors and the
numbers a case's parameter may be bound to.  A case without a case file (a researcher's scene.xml and
equations.py) gets its coordinates, bindings and time scales from this (dyncheck.case.derived), and
`dyncheck new` its scaffold."""

from dataclasses import dataclass

import mujoco
import numpy as np

from engines.bindings import SceneLocation

PLACEHOLDER_INERTIA = 1e-14  # kg m^2: the placeholder of docs/own-case.md (dyncheck.case.scene holds cases to it)
PLACEHOLDER_MASS = 1e-12  # kg: a body that only carries a joint (its mass means none)


@dataclass(frozen=True)
class Joint:
    name: str
    kind: str  # "hinge" | "slide" | "ball" | "free"
    body: str
    range: tuple | None  # (lower, upper) where the joint is limited, in rad or m


@dataclass(frozen=True)
class Value:
    """A number of the compiled scene that a parameter can set: its place (as case.toml's [scene.bindings] names
    it) and its value there."""
    location: SceneLocation
    value: float


@dataclass(frozen=True)
class SceneFile:
    path: str
    joints: tuple  # of Joint, in the file's order
    force_sensors: dict  # sensor name -> the body its site is on
    torque_sensors: dict  # sensor name -> the body its site is on
    values: tuple  # of Value
    masses: dict  # body name -> mass, kg
    length: float  # the largest distance between two bodies' origins or a body and its centre of mass, m
    loops: dict  # <equality> name -> its body1 (engines.loops: each a <connect> closing a loop)
    point_masses: tuple  # the bodies with mass whose inertia is a placeholder's (each moment at most PLACEHOLDER_INERTIA)


def describe(path):
    """The scene file at `path` as dyncheck reads it; ValueError naming the file if MuJoCo cannot compile it."""
    try:
        m = mujoco.MjSpec.from_file(str(path)).compile()
    except ValueError as error:
        hint = (" (a body that only carries a joint needs a placeholder: mass at most 1e-12 kg, inertia "
                "1e-14 kg m^2, docs/own-case.md)" if "mjMINVAL" in str(error) else "")
        raise ValueError(f"{path}: {error}{hint}") from None
    name = lambda kind, i: mujoco.mj_id2name(m, kind, i)
    body_name = lambda b: name(mujoco.mjtObj.mjOBJ_BODY, b)
    joints = tuple(Joint(name(mujoco.mjtObj.mjOBJ_JOINT, j), mujoco.mjtJoint(m.jnt_type[j]).name[6:].lower(),
                         body_name(m.jnt_bodyid[j]), tuple(map(float, m.jnt_range[j])) if m.jnt_limited[j] else None)
                   for j in range(m.njnt))
    sensors = {kind: {name(mujoco.mjtObj.mjOBJ_SENSOR, s): body_name(m.site_bodyid[m.sensor_objid[s]])
                      for s in range(m.nsensor) if m.sensor_type[s] == kind}
               for kind in (mujoco.mjtSensor.mjSENS_FORCE, mujoco.mjtSensor.mjSENS_TORQUE)}
    values = [Value(SceneLocation("option", "gravity", index=i), float(m.opt.gravity[i]))
              for i in range(3) if m.opt.gravity[i]]
    for b in range(1, m.nbody):
        body = body_name(b)
        values.append(Value(SceneLocation("body", body, "mass"), float(m.body_mass[b])))
        for attribute in ("pos", "ipos"):
            array = getattr(m, "body_" + attribute)[b]
            values += [Value(SceneLocation("body", body, attribute, i), float(array[i]))
                       for i in range(3) if array[i]]
        # The principal moments about the centre of mass, where their axes are the body's (a diaginertia, or a
        # fullinertia that is diagonal): a placeholder's (at most PLACEHOLDER_INERTIA) means no inertia.
        if np.allclose(m.body_iquat[b], [1.0, 0.0, 0.0, 0.0], rtol=0.0, atol=1e-12):
            values += [Value(SceneLocation("body", body, "inertia", i), float(m.body_inertia[b][i]))
                       for i in range(3) if m.body_inertia[b][i] > PLACEHOLDER_INERTIA]
    for j, joint in enumerate(joints):
        scalar = joint.kind in ("hinge", "slide")
        for attribute, value in (("stiffness", m.jnt_stiffness[j]), ("damping", m.dof_damping[m.jnt_dofadr[j]]),
                                 ("springref", m.qpos_spring[m.jnt_qposadr[j]] if scalar else 0.0)):
            if value:
                values.append(Value(SceneLocation("joint", joint.name, attribute), float(value)))
    lengths = [np.linalg.norm(m.body_pos[b]) for b in range(1, m.nbody)] + \
              [np.linalg.norm(m.body_ipos[b]) for b in range(1, m.nbody)]
    return SceneFile(str(path), joints, sensors[mujoco.mjtSensor.mjSENS_FORCE], sensors[mujoco.mjtSensor.mjSENS_TORQUE],
                     tuple(values),
                     {body_name(b): float(m.body_mass[b]) for b in range(1, m.nbody)}, float(max(lengths, default=0.0)),
                     {name(mujoco.mjtObj.mjOBJ_EQUALITY, e) or str(e): body_name(_body1(m, e)) for e in range(m.neq)},
                     tuple(body_name(b) for b in range(1, m.nbody)
                           if m.body_mass[b] > PLACEHOLDER_MASS and np.all(m.body_inertia[b] <= PLACEHOLDER_INERTIA)))


def _body1(m, e):
    """The body that carries equality e's first point (its body1, or its site1's body)."""
    first = m.eq_obj1id[e]
    return m.site_bodyid[first] if m.eq_objtype[e] == mujoco.mjtObj.mjOBJ_SITE else first
