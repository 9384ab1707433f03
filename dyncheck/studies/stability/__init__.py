"""Stability studies: where integration methods fail, where the physics itself runs away, where the
book's formulation is singular, how long a chaotic trajectory can be trusted.

Each case says in its `[stability]` table which studies it gets and with what numbers, each study
in a sub-table named after it with a `why`.  Studies that apply to any scene are here
(`long_runs`: the finite-time Lyapunov exponent and agreement horizon, the long-run energy drift);
a case's own studies live in the file its table names as `module`, whose `STUDIES` maps names to
`common.Study` (run, figure, required keys), as the `studies.py` of two of the book's cases do (the
largest stable step against a stiffness; the Euler-angle singularity and the sleeping top).

`studies(case)` runs them and returns one dyncheck.results.values.StudyResult per study; `figure(case,
result, path)` draws one and returns its caption.  `validate(case)` checks the table at load.  A run that blows up (NaN, a
state beyond its physical bound, MuJoCo resetting the simulation) is data: status "unstable" with
time and step, never an exception out of a study and never a NaN in its table.

`long_runs.agreement_horizon(case)` is for the trajectory check: how long two sources that differ by the
integrators' error level can be expected to agree to a tolerance, from the finite-time growth of
perturbations along the book's initial conditions (cheap: five trajectories over the case's horizon).
"""

from dyncheck.case import files
from dyncheck.case.folder import settings_of
from dyncheck.case.isolation import load_file
from dyncheck.common import ceilings
from dyncheck.results.values import heading
from dyncheck.studies.stability.common import NotApplicable, Study, not_applicable
from dyncheck.studies.stability.long_runs import energy_drift, figure_energy_drift, figure_lyapunov, lyapunov

# The studies any case may name.
GENERIC = {
    "lyapunov": Study(lyapunov, figure_lyapunov, ("initial", "horizon", "renormalise", "d0", "rtol", "eps0", "tol",
                                                  "check_rtol", "rate_scale")),
    "energy_drift": Study(energy_drift, figure_energy_drift, ("methods", "horizon", "dt", "rtol", "output_step")),
}
NOT_STUDIES = ("why", "module")  # the table's own keys


def case_module(case):
    """The case's own study module ([stability] module, a .py file in its folder; case.load_file); None
    for a case without one."""
    module = case.spec.get("stability", {}).get("module")
    if module is None:
        return None
    path = files.own_file(case.folder, module, "stability.module", case.file)
    if not path.is_file():  # also when saved results are rendered after their case folder moved
        raise ValueError(f"{case.origin}: stability.module = {module!r}: no such Python file {path} (the case's "
                         "studies and the figures of their saved results need it)")
    return load_file(path, f"{case.origin}: stability.module = {module!r}")


def available(case):
    """The studies `case` may name: the generic ones and those of its own module."""
    module = case_module(case)
    if module is None:
        return GENERIC
    own = getattr(module, "STUDIES", None)
    if not isinstance(own, dict) or not all(isinstance(s, Study) for s in own.values()):
        raise ValueError(f"{module.__file__}: STUDIES is {type(own).__name__}, not a dict of "
                         "dyncheck.studies.stability.common.Study")
    if GENERIC.keys() & own.keys():
        raise ValueError(f"{module.__file__}: STUDIES names {sorted(GENERIC.keys() & own.keys())}, which are "
                         "dyncheck's own studies; give yours other names")
    return {**GENERIC, **own}


def validate(case):
    """The case's [stability] table: known studies, each with a `why` and its keys, methods that exist,
    numbers that evaluate; ValueError names the file and the field."""
    from dyncheck.common.ceilings import LEAST_RTOL
    from dyncheck.run.simulate import METHODS
    table = case.spec.get("stability", {})
    if not isinstance(table, dict):
        raise ValueError(f"{case.origin}: stability is not a table")
    if not isinstance(table.get("module", ""), str):
        raise ValueError(f"{case.origin}: stability.module = {table['module']!r} is not a file name")
    studies = available(case)
    for key, value in table.items():
        if key in NOT_STUDIES:
            continue
        if key not in studies:
            raise ValueError(f"{case.origin}: stability.{key} is not a known study; studies are {', '.join(studies)}")
        if not isinstance(value, dict) or not isinstance(value.get("why"), str):
            raise ValueError(f"{case.origin}: stability.{key} needs a `why` string")
        missing = [k for k in studies[key].keys if k not in value]
        if missing:
            raise ValueError(f"{case.origin}: stability.{key} lacks {', '.join(missing)}")
        for method in value.get("methods", []) + ([value["method"]] if "method" in value else []):
            if method not in METHODS:
                raise ValueError(f"{case.origin}: stability.{key}.methods: unknown method '{method}'")
        for name, override in value.get("overrides", {}).items():
            if name not in case.params:
                raise ValueError(f"{case.origin}: stability.{key}.overrides: no parameter '{name}'")
        try:  # the study's case must be physical too
            case.with_params(**value.get("overrides", {}))
        except ValueError as error:
            raise ValueError(f"stability.{key}.overrides = {value.get('overrides')}: {error}") from None
        settings = settings_of(case, key)  # a ValueError names the file and the field
        for name in ("rtol", "check_rtol"):  # scipy raises a smaller rtol to LEAST_RTOL: not the run the study says
            if name in settings and not settings[name] >= LEAST_RTOL:
                raise ValueError(f"{case.origin}: stability.{key}.{name} = {settings[name]!r} is below {LEAST_RTOL:.3g}, "
                                 "the least rtol scipy's integrators honour (dyncheck.common.ceilings.LEAST_RTOL)")
        if key == "lyapunov":
            _agreement_settings(case.origin, settings)
        if key == "energy_drift" and not hasattr(case.model("reference"), "energy"):
            raise ValueError(f"{case.origin}: stability.energy_drift measures the drift of the derivation's energy, "
                             f"and {case.spec['derivation']} defines no energy(t, q, v, p); add it or remove the study")


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
    studies = available(case)
    out = []
    for name in case.spec.get("stability", {}):
        if name in NOT_STUDIES:
            continue
        if progress:
            progress(f"{case.name}: stability study {name}")
        settings = settings_of(case, name)
        try:
            out.append(studies[name].run(case, settings, progress))
        except NotApplicable as why:
            out.append(not_applicable(case, name, settings, why))
    return out


# -- figures ------------------------------------------------------------------------------------

def figure(case, result, path):
    """Draw a study's result to the PNG `path` (and its PDF twin), titled with the case's heading; returns
    the figure's caption, from the study: what it shows and what to see in it.  None, drawing nothing, for a
    study that was not applicable (it has nothing to draw)."""
    if not result.series:
        return None
    return available(case)[result.study].figure(result, path, heading(case.spec))
