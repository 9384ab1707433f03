"""Stability studies: where integration methods fail, where the physics itself runs away, where the
book's formulation is singular, how long a chaotic trajectory can be trusted (DESIGN.md, "Studies").

Each case says in its `[stability]` table which studies it gets and with what numbers, each study
in a sub-table named after it with a `why`; the studies of a case live in the module named after it,
what they share in `common`:

    spring_pendulum   [stability.stable_step]        largest stable step of each method against k
    double_pendulum   [stability.lyapunov]           finite-time Lyapunov exponent, agreement horizon
                      [stability.energy_drift]       long-run energy error of each method
    spinning_top      [stability.euler_singularity]  the Euler-angle equations near zero nutation
                      [stability.sleeping_top]       the least spin of a stable upright top

`studies(case)` runs them and returns one result per study, a dict:

    case, study, title, why      names and the case file's reason for the study's numbers
    data                         tidy DataFrame of every number measured (NaN only where a status
                                 column says why there is no number)
    table                        the same for display: strings, no NaN ("unstable at t = ... (step n)")
    findings                     plain-English sentences with the numbers, for the report page
    series                       what the figure draws (arrays, theory curves)
    settings                     the study's settings as used (expressions evaluated)
    wall                         seconds the study took
    data_passages                (euler_singularity only) the trajectories through the near-upright

and `figure(result, path)` draws its PNG.  `validate(case)` checks the table (studies() calls it).
A run that blows up (NaN, a state beyond its physical bound, MuJoCo resetting the simulation) is data: status "unstable" with time and step, never an
exception out of a study and never a NaN in `table`.

`agreement_horizon(case)` is for the trajectory check: how long two sources that differ by the
integrators' error level can be expected to agree to a tolerance, from the finite-time growth of
perturbations along the book's initial conditions (cheap: five trajectories over the case's horizon).
"""

from dyncheck import ceilings

# The package's interface: the studies, their figures, and the pieces the tests and checks call.
from dyncheck.stability.common import SHARP, _settings, attempt, describe, limit_step, run_fixed, spectral_radius  # noqa: F401
from dyncheck.stability.double_pendulum import (agreement_horizon, benettin, energy_drift, figure_energy_drift,  # noqa: F401
                                                figure_lyapunov, lyapunov)
from dyncheck.stability.spinning_top import euler_singularity, figure_euler_singularity, figure_sleeping_top, sleeping_top
from dyncheck.stability.spring_pendulum import figure_stable_step, spring_linearisation, stable_step  # noqa: F401


# -- dispatch -----------------------------------------------------------------------------------

STUDIES = {"stable_step": stable_step, "lyapunov": lyapunov, "energy_drift": energy_drift,
           "euler_singularity": euler_singularity, "sleeping_top": sleeping_top}


REQUIRED = {
    "stable_step": ("k", "methods", "horizon", "growth", "resolution", "escape", "max_steps", "rtol", "k_resolution",
                    "output_rows"),
    "lyapunov": ("initial", "horizon", "renormalise", "d0", "rtol", "eps0", "tol", "check_rtol"),
    "energy_drift": ("methods", "horizon", "dt", "rtol", "output_step"),
    "euler_singularity": ("nutation", "precession", "spin_angle", "spin", "transverse", "direction", "passage_spin",
                          "start_nutation", "miss", "passage_horizon", "passage_output", "mujoco_step", "rtol"),
    "sleeping_top": ("start_nutation", "bound", "horizon", "mujoco_step", "bracket", "resolution"),
}
"""The keys each study's table must have (besides `why`); optional: `source`, `overrides`, `method`, `k_stiff`."""


def validate(case):
    """The case's [stability] table: known studies, each with a `why` and its keys, methods that exist,
    numbers that evaluate; ValueError names the file and the field."""
    from dyncheck.simulate import METHODS
    table = case.spec.get("stability", {})
    if not isinstance(table, dict):
        raise ValueError(f"{case.file}: stability is not a table")
    for key, value in table.items():
        if key == "why":
            continue
        if key not in STUDIES:
            raise ValueError(f"{case.file}: stability.{key} is not a known study; studies are {', '.join(STUDIES)}")
        if not isinstance(value, dict) or not isinstance(value.get("why"), str):
            raise ValueError(f"{case.file}: stability.{key} needs a `why` string")
        missing = [k for k in REQUIRED[key] if k not in value]
        if missing:
            raise ValueError(f"{case.file}: stability.{key} lacks {', '.join(missing)}")
        for method in value.get("methods", []) + ([value["method"]] if "method" in value else []):
            if method not in METHODS:
                raise ValueError(f"{case.file}: stability.{key}.methods: unknown method '{method}'")
        for name, override in value.get("overrides", {}).items():
            if name not in case.params:
                raise ValueError(f"{case.file}: stability.{key}.overrides: no parameter '{name}'")
        settings = _settings(case, key)  # a ValueError names the file and the field
        if key == "lyapunov":
            _agreement_settings(case.file, settings)


def _agreement_settings(file, settings):
    """eps0 and tol set the trajectory check's agreement horizon: two sources that differ by eps0 are
    compared until their difference could reach tol, so 0 < eps0 < tol, and tol no more than the
    ceiling of a run's comparison (above it an error estimate means nothing)."""
    eps0, tol = settings["eps0"], settings["tol"]
    if not 0 < eps0 < 1:
        raise ValueError(f"{file}: stability.lyapunov.eps0 = {eps0!r} is not a relative error level in (0, 1)")
    if not eps0 < tol <= ceilings.RUN:
        raise ValueError(f"{file}: stability.lyapunov.tol = {tol!r} is not in (eps0 = {eps0:g}, {ceilings.RUN:g}]: "
                         "the agreement horizon would compare nothing, or compare beyond where an error estimate "
                         "means anything")


def studies(case, progress=None):
    """Every study the case's [stability] table declares, in its order: a list of results (see the module)."""
    validate(case)
    out = []
    for name in case.spec.get("stability", {}):
        if name == "why":
            continue
        if progress:
            progress(f"{case.name}: stability study {name}")
        out.append(STUDIES[name](case, _settings(case, name), progress))
    return out


# -- figures ------------------------------------------------------------------------------------

def figure(result, path):
    """Draw a study's result to the PNG `path`."""
    {"stable_step": figure_stable_step, "lyapunov": figure_lyapunov, "energy_drift": figure_energy_drift,
     "euler_singularity": figure_euler_singularity, "sleeping_top": figure_sleeping_top}[result["study"]](result, path)
    return path
