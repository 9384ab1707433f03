"""`dyncheck new`: the files of a new case on an MJCF scene, an equations.py with its coordinates, parameters and
signatures filled in and a case.toml that binds each parameter to its scene number (dyncheck.case.derived reads
them back as any two-file case)."""

from dyncheck.case.derived import ABOUT, AXES, SIGNED, binding_table, component, toml_value


def scaffold(name, scene):
    """The files of a new case on `scene` (engines.mjcf.SceneFile), as `dyncheck new` writes them: an
    equations.py with the coordinates, parameters and signatures filled in, and a case.toml that binds
    each parameter to its scene number (so that equal numbers are no ambiguity)."""
    scalar = [j for j in scene.joints if j.kind in ("hinge", "slide")]
    params = {}  # name -> (value, binding table, about)
    for v in scene.values:
        location, attribute = v.location, v.location.attribute
        if attribute == "mass" and v.value <= 1e-12:  # a placeholder: no parameter
            continue
        owner = location.name  # the body's or joint's (not the case's `name`)
        label = {"mass": f"m_{owner}", "stiffness": f"k_{owner}", "damping": f"c_{owner}", "springref": f"{owner}_rest",
                 None: "g", "pos": f"{owner}_pos_{AXES[location.index]}", "ipos": f"{owner}_com_{AXES[location.index]}",
                 "inertia": f"I{AXES[location.index] * 2}_{owner}"}[attribute]
        scale = -1.0 if v.value < 0 and attribute in SIGNED else 1.0
        params[label] = (scale * v.value, binding_table(location, scale),
                         ABOUT[attribute].format(name=owner, index=component(location)))
    dampers = [j.name for j in scalar if f"c_{j.name}" in params]
    coords = [j.name for j in scalar]
    unpack = lambda names: ", ".join(names) + ("," if len(names) == 1 else "")
    rates = [f"{c}_rate" for c in coords]
    joints = "; ".join(f"{j.name} ({j.kind}, {'rad' if j.kind == 'hinge' else 'm'})" for j in scalar)
    entries = {p: f'"{p}": {value!r},' for p, (value, _, _) in params.items()}
    width = max(map(len, entries.values()), default=0)
    param_lines = "\n".join(f"    {entries[p]:<{width}}  # {about}" for p, (_, _, about) in params.items())
    equations = f'''"""{name}: <what the mechanism is, in one line>.

<The mechanism and its coordinates in a paragraph: this opens the case's report.>
"""
import numpy as np

# The generalized coordinates, one per joint of scene.xml: {joints}.
COORDS = {coords!r}

# The parameters, SI units.  Each is bound to the scene number written next to it in case.toml, so that
# --set and the random parameter sets change scene.xml and these equations alike.  Rename them as your
# derivation does (in case.toml too); delete those it does not use.
PARAMS = {{
{param_lines}
}}


def mass_matrix(q, p):
    """M(q) of the equations of motion M(q) q'' = f(t, q, q')."""
    {unpack(coords)} = q
    raise NotImplementedError("mass_matrix: write M(q)")


def forces(t, q, v, p):
    """f(t, q, q'): everything but M(q) q'' (gravity, springs, centripetal and Coriolis terms), on the right."""
    {unpack(coords)} = q
    {unpack(rates)} = v
    raise NotImplementedError("forces: write f(t, q, q')")


def accelerations(t, q, v, p):
    """q'' = M^-1 f: what the engines are compared with."""
    return np.linalg.solve(mass_matrix(q, p), forces(t, q, v, p))


def energy(t, q, v, p):
    """Kinetic plus potential energy (gravity's zero at the world origin, springs' at coordinate 0), J.
    Optional: without it the derivation's energy rows are not applicable (the engines' stay)."""
    {unpack(coords)} = q
    {unpack(rates)} = v
    raise NotImplementedError("energy: write T + V")
''' + ('' if not dampers else f'''

def drive_power(t, q, v, p):
    """The power put in and taken out, W: each damper takes c q'^2 (the work-energy balance of a damped scene
    needs it, docs/model-interface.md).  Add what any applied force puts in."""
    {unpack(rates)} = v
    return -({' + '.join(f'p["c_{j}"] * {j}_rate**2' for j in dampers)})
''')
    bindings = "\n".join(f"{p} = [{{ {', '.join(f'{k} = {toml_value(x)}' for k, x in table.items())} }}]"
                         for p, (_, table, _) in params.items())
    case_toml = f'''# What dyncheck cannot read from scene.xml and equations.py alone (docs/own-case.md).  Everything
# else (units, horizon, steps, tolerances, random states) is derived; any table of docs/case-file.md
# written here replaces the derived one.

[scene.bindings]
{bindings}
'''
    return equations, case_toml
