"""Stability studies: where integration methods fail, where the physics itself runs away, where the
book's formulation is singular, how long a chaotic trajectory can be trusted (DESIGN.md, "Studies").

Each case says in its `[stability]` table which studies it gets and with what numbers, each study
in a sub-table named after it with a `why`:

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

and `figure(result, path)` draws its PNG.  `validate(case)` checks the table (studies() calls it).  A run that blows up (NaN, a state beyond its physical
bound, MuJoCo resetting the simulation) is data: status "unstable" with time and step, never an
exception out of a study and never a NaN in `table`.

`agreement_horizon(case)` is for the trajectory check: how long two sources that differ by the
integrators' error level can be expected to agree to a tolerance, from the finite-time growth of
perturbations along the book's initial conditions (cheap: five trajectories over the case's horizon).
"""

import math
import time
from fractions import Fraction

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, fsolve

from dyncheck.case import load_case
from dyncheck.simulate import FIXED_METHODS, MUJOCO_METHODS, SCIPY_METHODS, Unstable, check_mujoco_run, simulate

SHARP = {"semi-implicit Euler": 2.0, "mujoco:Euler": 2.0, "mujoco:implicitfast": 2.0,
         "RK4": 2 * math.sqrt(2.0), "mujoco:RK4": 2 * math.sqrt(2.0)}
"""omega h limits of the schemes on an undamped oscillator x'' = -omega^2 x (eigenvalues +-i omega):
semi-implicit (symplectic) Euler |x| < 2; classical RK4 on the imaginary axis |x| < 2 sqrt(2) = 2.83
(2.785 is its limit on the negative real axis, for decaying modes); MuJoCo's Euler is the same
semi-implicit Euler, and its implicitfast treats only velocity-dependent forces implicitly, so an
undamped spring is explicit to it.  Explicit Euler grows by sqrt(1 + (omega h)^2) every step, for
any h: it has no limit, only a horizon (see `limit_step`)."""

EPS = np.finfo(float).eps


# -- runs that may blow up --------------------------------------------------------------------

def failure(error):
    """An integration that blew up, as data: {status, t, step, why}."""
    if isinstance(error, Unstable):
        return {"status": "unstable", "t": float(error.t), "step": int(error.step), "why": str(error.why)}
    return {"status": "unstable", "t": None, "step": None, "why": f"{type(error).__name__}: {error}"}


def attempt(run):
    """(result, None) or (None, failure): a blow-up is recorded, never raised."""
    try:
        with np.errstate(all="ignore"):
            return run(), None
    except (Unstable, ArithmeticError, np.linalg.LinAlgError) as error:
        return None, failure(error)


def describe(fail):
    """'unstable at t = 0.31 s (step 62): why' for a failure dict."""
    if fail is None:
        return "ran"
    when = f" at t = {fail['t']:.4g} s" if fail.get("t") is not None else ""
    step = f" (step {fail['step']})" if fail.get("step") is not None else ""
    return f"{fail['status']}{when}{step}: {fail['why']}"


class Guarded:
    """`model` whose accelerations raise Unstable once coordinate `index` leaves +-`bound` (or is not
    finite): a run that has left the physics stops there, with its time and step."""

    def __init__(self, model, index, bound, method, per_step=1):
        self.model, self.index, self.bound, self.method, self.per_step = model, index, bound, method, per_step
        self.coords, self.reaction_names = model.coords, model.reaction_names
        self.evaluations = 0

    def accelerations(self, t, q, v):
        self.evaluations += 1
        x = q[self.index]
        if not -self.bound <= x <= self.bound:  # NaN fails too
            raise Unstable(self.method, t, self.evaluations // self.per_step,
                           f"|{self.coords[self.index]}| = {abs(x):.3g} beyond {self.bound:g}")
        return self.model.accelerations(t, q, v)

    def reactions(self, t, q, v):
        return self.model.reactions(t, q, v)

    def energy(self, t, q, v):
        return self.model.energy(t, q, v)

    def drive_power(self, t, q, v):
        return self.model.drive_power(t, q, v)


def evaluations_per_step(method):
    return {"RK4": 4}.get(method, 1) if method in FIXED_METHODS else 1


def grid_step(dt_target, t_end, max_out=1000):
    """(dt, steps, every): the largest step dt <= dt_target that divides t_end, output every `every`
    steps, at most `max_out` rows."""
    steps = max(1, math.ceil(t_end / dt_target - 1e-9))
    every = max(1, math.ceil(steps / max_out))
    steps = every * math.ceil(steps / every)
    return t_end / steps, steps, every


def run_fixed(case, source, method, dt_target, t_end, *, bound=None, index=None, max_out=1000):
    """`method` at the step of `grid_step`: fixed-step generic methods integrate `source` (guarded by
    `bound` on coordinate `index`), MuJoCo's its own scene.  Returns (run, dt, steps) or raises Unstable."""
    dt, steps, every = grid_step(dt_target, t_end, max_out)
    if method in MUJOCO_METHODS:
        model = case.model("mujoco")
        if bound is not None:  # no guard inside MuJoCo's loop: look at its raw steps first
            _mujoco_bound(model, case.initial[:2], t_end, dt, method, bound, index)
    else:
        model = case.model(source)
        if bound is not None:
            model = Guarded(model, index, bound, method, evaluations_per_step(method))
    run = simulate(model, case.initial[:2], t_end, method, dt=dt, output_step=every * dt, work=False)
    return run, dt, steps  # simulate raises Unstable at a non-finite state or a MuJoCo reset


def _mujoco_bound(model, ic, t_end, dt, method, bound, index):
    """Raise Unstable at MuJoCo's first step beyond `bound` on coordinate `index`, non-finite, or reset."""
    run = model.step(ic[0], ic[1], t_end, dt, method.split(":")[1])
    check_mujoco_run(run, method, dt, (model.coords[index], index, bound))


# -- linear stability of one-step schemes -------------------------------------------------------

FAMILY = {"explicit Euler": "explicit Euler", "semi-implicit Euler": "semi-implicit Euler",
          "mujoco:Euler": "semi-implicit Euler", "mujoco:implicitfast": "semi-implicit Euler",
          "RK4": "RK4", "mujoco:RK4": "RK4"}


def spectral_radius(method, x):
    """Spectral radius of one step of `method` on x'' = -omega^2 x, for omega h = x (array or scalar):
    explicit Euler sqrt(1 + x^2); semi-implicit Euler (the rate first, the position with the new rate:
    trace 2 - x^2, determinant 1) 1 up to x = 2; classical RK4 |R(i x)| = sqrt(1 - x^6/72 + x^8/576)."""
    x = np.asarray(x, dtype=float)
    family = FAMILY.get(method)
    if family == "explicit Euler":
        return np.sqrt(1.0 + x * x)
    if family == "semi-implicit Euler":
        half = np.abs(1.0 - x * x / 2)
        return np.where(half <= 1.0, 1.0, half + np.sqrt(np.maximum(half * half - 1.0, 0.0)))
    if family == "RK4":
        return np.sqrt(1.0 - x**6 / 72 + x**8 / 576)
    raise ValueError(f"no stability theory for method '{method}'")


def limit_step(method, omega, span, growth):
    """The largest h for which `method` amplifies an undamped oscillation of frequency omega by at
    most `growth` over `span` seconds: the first h with rho(omega h)^(span/h) = growth.  For the
    sharp methods this is their omega h limit pushed up by a hair; for explicit Euler, whose
    spectral radius sqrt(1 + (omega h)^2) exceeds 1 for every h, it is h ~ 2 ln(growth)/(omega^2 span)."""
    if not omega > 0:
        return math.inf
    excess = lambda h: span / h * np.log(spectral_radius(method, omega * h)) - math.log(growth)
    grid = np.geomspace(1e-7, 8.0, 1500) / omega
    above = np.nonzero(excess(grid) > 0)[0]
    if not above.size:
        return math.inf
    i = above[0]
    return brentq(lambda h: float(excess(h)), grid[i - 1], grid[i], xtol=1e-14, rtol=1e-12) if i else grid[0]


# -- common -------------------------------------------------------------------------------------

def _settings(case, name):
    """The study's sub-table with its expressions evaluated (numbers stay numbers)."""
    raw = case.spec["stability"][name]
    out = {}
    for key, x in raw.items():
        if key in ("why", "methods", "initial", "overrides", "source", "method"):
            out[key] = x
        elif isinstance(x, list):
            out[key] = [case.value(y) for y in x]
        else:
            out[key] = case.value(x)
    return out


def _variant(case, **params):
    """The case with further parameter overrides (on top of the case's own)."""
    return load_case(case.name, **{**case.overrides, **params})


def _fmt(x, spec=".3g", none="-"):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return none
    return format(x, spec)


def _result(case, study, title, settings, data, table, findings, series, start):
    table = table.astype(object).where(table.notna(), "-").astype(str)
    return {"case": case.name, "study": study, "title": title, "why": " ".join(settings.get("why", "").split()),
            "data": data, "table": table, "findings": findings, "series": series,
            "settings": {k: v for k, v in settings.items() if k != "why"}, "wall": time.perf_counter() - start}


def _rms(x):
    x = np.asarray(x, dtype=float)
    return float(np.sqrt(np.mean(x * x))) if x.size else float("nan")


# == 1. spring pendulum: the largest stable step against the stiffness ==========================

def spring_linearisation(case, k):
    """The spring pendulum's relative equilibrium on the disk and its two frequencies at stiffness k.

    The base turns at Omega = alpha' + beta' about the vertical; seen from the disk, the particle
    feels gravity, the centrifugal field Omega^2 (r + L sin psi) and, from the arm, the centripetal
    acceleration b alpha'^2 of the disk's centre, which turns in the disk frame at beta' and averages
    out: it is dropped (b = 0), so that an equilibrium exists.  Coriolis forces are normal to the
    pendulum's plane (the arm takes them), so the linearised motion is conservative:
    M q'' = -H q with H the Hessian of the effective potential
        V/m = -g L cos psi - Omega^2 (r + L sin psi)^2 / 2 + (k/m) l^2 / 2,   L = l0 + l,
    whose l-stiffness k/m - Omega^2 sin^2 psi is the spring softened by the spin.  As k falls to
    k_crit = m Omega^2 the equilibrium moves out to l -> infinity (psi -> pi/2): below k_crit the
    spring cannot hold the particle.  Returns (psi*, l*, omega_slow, omega_fast) or None below."""
    p = dict(case.params, k=k, b=0.0)
    book = type(case.model("book"))(p)
    omega = p["alpha_rate"] + p["beta_rate"]
    if k <= p["m"] * omega**2:
        return None
    f = lambda q: book.accelerations(0.0, q, np.zeros(2))
    # Start far out for a soft spring (l* ~ Omega^2 (r + l0) / (k/m - Omega^2) there).
    guess = np.array([1.5, (p["g"] + omega**2 * (p["r"] + p["l0"])) / (k / p["m"] - omega**2)])
    q, info, ok, _ = fsolve(f, guess, xtol=1e-13, full_output=True)
    if ok != 1 or q[1] <= -p["l0"]:
        return None
    h = 1e-7 * max(1.0, abs(q[1]))
    jac = np.column_stack([(f(q + h * e) - f(q - h * e)) / (2 * h) for e in np.eye(2)])
    w2 = np.sort(np.linalg.eigvals(-jac).real)
    if w2[0] <= 0:
        return None
    return q[0], q[1], math.sqrt(w2[0]), math.sqrt(w2[1])


def _window_ratios(frame, t_end, model):
    """For each coordinate, the RMS of its acceleration over the last quarter of [0, t_end] over that of
    the first quarter."""
    t = frame.index.to_numpy()
    q = frame[list(model.coords)].to_numpy()
    v = frame[[c + "_rate" for c in model.coords]].to_numpy()
    acc = np.array([model.accelerations(ti, qi, vi) for ti, qi, vi in zip(t, q, v)])
    first, last = t <= t_end / 4, t >= 3 * t_end / 4
    return np.array([_rms(acc[last, i]) / _rms(acc[first, i]) for i in range(acc.shape[1])])


def _growth(run, exact_ratios, t_end, model):
    """How much more the run's oscillation grew than the exact one's: for psi'' and l'' (the net forces,
    in which the fast spring mode dominates: its acceleration is omega^2 times its amplitude), the RMS
    over the last quarter of the horizon over that of the first quarter (`_window_ratios`), divided by
    the same ratio of the exact solution; the larger of the two.  For an envelope growing like
    exp(gamma t) it is exp(gamma 3T/4)."""
    return float(np.max(_window_ratios(run, t_end, model) / exact_ratios))


def _search(trial, start, resolution, down=1.5, up=1.5, tries=12):
    """Bracket and bisect the first failure from below: trial(h) -> (h actually used, ok).  Returns
    (largest ok h, smallest failing h above it), either None if not found within `tries` moves."""
    h, ok = trial(start)
    lo = hi = None
    for _ in range(tries):
        if ok:
            lo = h
            if hi is not None:
                break
            h, ok = trial(h * up)
        else:
            hi = h
            if lo is not None:
                break
            h, ok = trial(h / down)
    while lo is not None and hi is not None and hi / lo > 1 + resolution:
        h, ok = trial(math.sqrt(lo * hi))
        if not lo < h < hi:  # the step grid (T / integer) cannot split the bracket further
            break
        if ok:
            lo = h
        else:
            hi = h
    return lo, hi


def stable_step(case, settings, progress=None):
    """Largest stable step of each method against the spring stiffness, from the book's initial conditions.

    Two steps per (k, method), each bisected (`_search`: the first failure from below):
    - h_stable: the run stays finite and within `escape`, and its oscillation grows at most `growth`
      times more than the exact solution's over the horizon (`_growth`);
    - h_blowup: the run leaves `escape` (100 m), turns non-finite or MuJoCo resets it.
    Linear theory (`spring_linearisation`, `limit_step`) predicts h_stable for every method and
    h_blowup for the sharp ones.  Below k_crit the exact solution itself runs away: each method is run
    once at a small step and its escape time compared with the exact one's."""
    start = time.perf_counter()
    p = case.params
    m, omega_base = p["m"], p["alpha_rate"] + p["beta_rate"]
    k_crit = m * omega_base**2
    T, G, resolution = settings["horizon"], settings["growth"], settings["resolution"]
    escape = settings["escape"]
    methods, source = settings["methods"], settings.get("source", "reference")
    span = 0.75 * T  # the growth is measured from the first quarter of the horizon to the last
    runaway_T = case.initial[2]
    rows, trail = [], []

    for k in settings["k"]:
        variant = _variant(case, k=k)
        if progress:
            progress(f"stable step, k = {k:g} N/m")
        lin = spring_linearisation(case, k)
        # The exact solution from the book's initial conditions: bounded, or a physical runaway?
        exact_model = Guarded(variant.model(source), 1, escape, "DOP853", 1)
        exact_long, fail = attempt(lambda: simulate(exact_model, variant.initial[:2], runaway_T, "DOP853",
                                                    rtol=settings["rtol"], output_step=1e-3, work=False))
        base = {"k": k, "omega_fast": lin[3] if lin else None, "omega_slow": lin[2] if lin else None,
                "psi_eq": lin[0] if lin else None, "l_eq": lin[1] if lin else None}
        if fail is not None:
            rows.append({**base, "method": "exact (DOP853)", "status": "physical runaway",
                         "t_fail": fail["t"], "why": fail["why"]})
            growth_rate = math.sqrt(max(omega_base**2 - k / m, 0.0))
            for method in methods:
                # The method at a step far inside its limits: it runs away too, with the exact solution.
                dt = 0.05 / omega_base if method != "explicit Euler" else 2e-4
                _, mfail = attempt(lambda: run_fixed(variant, source, method, dt, runaway_T, bound=escape, index=1))
                mfail = mfail or {"t": None, "step": None, "why": "stayed within the bound"}
                rows.append({**base, "method": method, "status": "physical runaway", "dt": dt,
                             "t_fail": mfail["t"], "t_exact": fail["t"], "step_fail": mfail.get("step"),
                             "why": f"exact solution escapes too (|l| > {escape:g} m at t = {fail['t']:.3g} s; "
                                    f"linear growth rate sqrt(Omega^2 - k/m) = {growth_rate:.3g} 1/s)"})
            continue
        exact = exact_long.loc[:T + 1e-12]
        rows.append({**base, "method": "exact (DOP853)", "status": "bounded",
                     "l_max": float(exact_long["l"].abs().max())})
        judge = variant.model(source)
        exact_ratios = _window_ratios(exact, T, judge)
        for method in methods:
            h_theory = limit_step(method, lin[3], span, G) if lin else None
            h_limit = SHARP[method] / lin[3] if lin and method in SHARP else None
            guess = h_theory or 2.0 / math.sqrt(k / m)
            if method == "explicit Euler" and T / guess > settings["max_steps"]:
                rows.append({**base, "method": method, "status": "not measured", "h_theory": h_theory,
                             "why": f"a trial would take {T / guess:.3g} steps (more than {settings['max_steps']:g})"})
                continue
            verdicts = {}

            def trial(h):
                h = grid_step(h, T)[0]
                key = round(T / h)
                if key not in verdicts:
                    out, fail = attempt(lambda: run_fixed(variant, source, method, h, T, bound=escape, index=1,
                                                          max_out=settings["output_rows"]))
                    if fail is not None:
                        verdicts[key] = {"blowup": True, "stable": False, "growth": None, **fail}
                    else:
                        g = _growth(out[0], exact_ratios, T, judge)
                        verdicts[key] = {"blowup": False, "stable": bool(g <= G), "growth": g,
                                         "status": "stable" if g <= G else "grew", "t": None, "step": None,
                                         "why": f"the oscillation grew {g:.3g} times"}
                    trail.append({"k": k, "method": method, "dt": h, **verdicts[key]})
                return h, verdicts[key]

            lo, hi = _search(lambda h: (lambda r: (r[0], r[1]["stable"]))(trial(h)),
                             guess / (1.5 if method == "explicit Euler" else 4.0), resolution)
            # Blow-up: the sharp methods' linear limit.  Explicit Euler has none (it grows at every step,
            # and when it leaves the bound depends on the amplitude): not searched.
            b_lo, b_hi = (_search(lambda h: (lambda r: (r[0], not r[1]["blowup"]))(trial(h)), h_limit, resolution)
                          if h_limit else (None, None))
            hi_v = verdicts.get(round(T / hi)) if hi else None
            b_v = verdicts.get(round(T / b_hi)) if b_hi else None
            rows.append({**base, "method": method, "status": "measured" if lo and hi else "bracket failed",
                         "h_stable": lo, "h_unstable": hi, "h_theory": h_theory,
                         "ratio": lo / h_theory if lo and h_theory else None,
                         "fail_status": hi_v["status"] if hi_v else None,
                         "growth_above": hi_v["growth"] if hi_v else None,
                         "why": describe(hi_v) if hi_v else None,
                         "h_blowup": b_hi, "h_no_blowup": b_lo, "h_limit": h_limit,
                         "blowup_ratio": b_hi / h_limit if b_hi and h_limit else None,
                         "t_fail": b_v.get("t") if b_v else None, "step_fail": b_v.get("step") if b_v else None,
                         "blowup_why": describe(b_v) if b_v else None, "trials": len(verdicts)})

    data = pd.DataFrame(rows)
    # k_crit confirmed with the exact solution: bisection on k between a runaway and a bounded k.
    crit = _critical_stiffness(case, settings, source, escape, runaway_T)
    # The book's own program: explicit Euler at its step over its run, at the case's k.
    listing = _listing_growth(case, settings, source)
    # Theory curves over the measured range.
    k_dense = np.geomspace(k_crit * 1.002, max(settings["k"]) * 1.2, 90)
    lins = [spring_linearisation(case, k) for k in k_dense]
    curves = {"k": k_dense, "omega_fast": np.array([lin[3] if lin else np.nan for lin in lins])}
    for method in methods:
        curves[method] = np.array([limit_step(method, lin[3], span, G) if lin else np.nan for lin in lins])
        if method in SHARP:
            curves[method + " limit"] = SHARP[method] / curves["omega_fast"]

    table_rows = []
    for r in rows:
        if r["status"] == "physical runaway":
            if r["method"] == "exact (DOP853)":
                value = f"physical runaway: |l| > {escape:g} m at t = {_fmt(r['t_fail'])} s"
            elif r.get("t_fail") is not None:
                value = f"runs away with it at t = {_fmt(r['t_fail'])} s (exact: {_fmt(r.get('t_exact'))} s)"
            else:
                value = f"stays within the bound (the exact solution escapes at {_fmt(r.get('t_exact'))} s)"
            blow = "-"
        elif r["method"] == "exact (DOP853)":
            value, blow = f"bounded, |l| <= {r['l_max']:.3g} m", "-"
        elif r["status"] == "measured":
            value = (f"{r['h_stable']:.3g} s" + (f" ({r['ratio']:.2f} x theory)" if r.get("ratio") else "")
                     + f"; above: {r['why']}")
            blow = (f"{r['h_blowup']:.3g} s" + (f" ({r['blowup_ratio']:.2f} x limit)" if r.get("blowup_ratio") else "")
                    + f": {r['blowup_why']}") if r.get("h_blowup") else "-"
        else:
            value, blow = f"{r['status']}: {r.get('why', '')}", "-"
        table_rows.append({"k [N/m]": f"{r['k']:g}", "method": r["method"],
                           "largest stable step (growth <= %g)" % G: value,
                           "theory [s]": _fmt(r.get("h_theory")),
                           "smallest blow-up step": blow,
                           "linear limit [s]": _fmt(r.get("h_limit"))})
    table = pd.DataFrame(table_rows)

    findings = _stable_step_findings(case, settings, data, crit, listing, k_crit, span)
    series = {"rows": data, "curves": curves, "k_crit": k_crit, "crit": crit, "listing": listing,
              "trail": pd.DataFrame(trail), "horizon": T, "growth": G, "k_book": case.params["k"]}
    data = data.assign(horizon=T, growth_limit=G)
    return _result(case, "stable_step", "Largest stable step against the spring stiffness", settings,
                   data, table, findings, series, start)


def _critical_stiffness(case, settings, source, escape, horizon):
    """Bisection on k for the exact solution from the book's initial conditions: runaway below, bounded above."""
    k_crit = case.params["m"] * (case.params["alpha_rate"] + case.params["beta_rate"]) ** 2

    def runs_away(k):
        variant = _variant(case, k=k)
        model = Guarded(variant.model(source), 1, escape, "DOP853", 1)
        _, fail = attempt(lambda: simulate(model, variant.initial[:2], horizon, "DOP853", rtol=settings["rtol"],
                                           output_step=horizon / 100, work=False))
        return fail is not None

    lo, hi = 0.5 * k_crit, 2.0 * k_crit
    if not runs_away(lo) or runs_away(hi):
        return {"lo": None, "hi": None, "theory": k_crit}
    while hi - lo > settings["k_resolution"] * k_crit:
        mid = 0.5 * (lo + hi)
        if runs_away(mid):
            lo = mid
        else:
            hi = mid
    return {"lo": lo, "hi": hi, "theory": k_crit}


def _listing_growth(case, settings, source):
    """The book's Matlab listing (explicit Euler at its own step over its run) against the exact solution:
    the linear theory's amplification of a free spring oscillation, exp(omega^2 dt t / 2) over the run,
    how far its l strays from the exact one, and how much larger its l'' RMS is over the last sixth."""
    program = case.model("program")
    dt = program.dt
    t_end = round(program.steps * dt / 0.01) * 0.01  # whole output intervals (the listing: 2.99995 s)
    exact, fail = attempt(lambda: simulate(case.model(source), case.initial[:2], t_end, "DOP853",
                                           rtol=settings["rtol"], output_step=dt * 4, work=False))
    out, fail2 = attempt(lambda: simulate(case.model(source), case.initial[:2], t_end, "explicit Euler", dt=dt,
                                          output_step=dt * 4, work=False))
    if fail or fail2:
        return None
    lin = spring_linearisation(case, case.params["k"])
    model = case.model(source)
    t = exact.index.to_numpy()
    acc = lambda f: np.array([model.accelerations(ti, qi, vi) for ti, qi, vi in
                              zip(t, f[list(model.coords)].to_numpy(), f[[c + "_rate" for c in model.coords]].to_numpy())])
    last = t >= 5 * t_end / 6
    return {"dt": dt, "t_end": t_end, "omega": lin[3], "whole_run": math.exp(lin[3] ** 2 * dt * t_end / 2),
            "l_error": float(np.max(np.abs(out["l"].to_numpy() - exact["l"].to_numpy()))),
            "l_range": float(exact["l"].max() - exact["l"].min()),
            "acc_ratio": _rms(acc(out)[last, 1]) / _rms(acc(exact)[last, 1])}


def _stable_step_findings(case, settings, data, crit, listing, k_crit, span):
    T, G = settings["horizon"], settings["growth"]
    m = case.params["m"]
    omega_base = case.params["alpha_rate"] + case.params["beta_rate"]
    out = [f"Stable means: over T = {T:g} s from the book's initial conditions the run stays finite, keeps "
           f"|l| within {settings['escape']:g} m, and its oscillation (the RMS of psi'' and of l'' over the last "
           f"quarter of T against the first) grows at most {G:g} times more than the exact solution's; it blows up "
           f"when it leaves {settings['escape']:g} m, turns non-finite or MuJoCo resets it. Steps are bisected to "
           f"{100 * settings['resolution']:.0f} % (the first failure from below). Theory: the linearisation about "
           f"the relative equilibrium on the disk; a method is stable while its growth over {span:g} s, "
           f"rho(omega h)^({span:g}/h), stays within {G:g}."]
    measured = data[data["status"] == "measured"]
    stiff = measured[measured["k"] >= settings.get("k_stiff", 3e4)]
    for method, group in measured.groupby("method", sort=False):
        if method.startswith("mujoco:"):
            continue  # compared with its textbook scheme below
        g = stiff[stiff["method"] == method]
        text = f"{method}: "
        if len(g) and g["ratio"].notna().all():
            text += (f"for k >= {g['k'].min():g} N/m the largest stable step is {g['ratio'].min():.2f}-"
                     f"{g['ratio'].max():.2f} times the linear theory")
            if g["blowup_ratio"].notna().all():
                text += f" and it blows up at {g['blowup_ratio'].min():.2f}-{g['blowup_ratio'].max():.2f} times its limit"
            text += "; "
        soft = group[group["k"] < g["k"].min()] if len(g) else group
        if len(soft) and soft["ratio"].notna().any():
            text += (f"for k = {soft['k'].min():g}-{soft['k'].max():g} N/m, nearer k_crit and with the pendulum's swing "
                     f"mixing in, {soft['ratio'].min():.2f}-{soft['ratio'].max():.2f} times")
            if soft["blowup_ratio"].notna().any():
                text += (f" (blow-up at {soft['blowup_ratio'].min():.2f}-{soft['blowup_ratio'].max():.2f} "
                         "times the limit)")
        out.append(text.rstrip("; ") + ".")
    ee = measured[measured["method"] == "explicit Euler"].dropna(subset=["h_stable"])
    sie = measured[measured["method"] == "semi-implicit Euler"].dropna(subset=["h_blowup"])
    k_fit = settings.get("k_fit", 1e4)
    big = lambda g: g[g["k"] >= k_fit]
    if len(big(ee)) >= 2 and len(big(sie)) >= 2:
        se = np.polyfit(np.log(big(ee)["k"]), np.log(big(ee)["h_stable"]), 1)[0]
        ss = np.polyfit(np.log(big(sie)["k"]), np.log(big(sie)["h_blowup"]), 1)[0]
        top = ee["k"].max()
        ratio = (sie[sie["k"] == top]["h_stable"].iloc[0] / ee["h_stable"].iloc[-1]
                 if (sie["k"] == top).any() else None)
        out.append(f"Explicit Euler is unstable at every step on an undamped oscillation (each step multiplies it "
                   f"by sqrt(1 + (omega h)^2)), so only a horizon makes a step usable: over {T:g} s its step falls "
                   f"like 1/k (log-log slope {se:.2f} for k >= {k_fit:g} N/m), semi-implicit Euler's blow-up step like "
                   f"1/sqrt(k) ({ss:.2f})" + (f"; at k = {top:g} N/m semi-implicit Euler's stable step is {ratio:.0f} "
                                               "times explicit Euler's." if ratio else "."))
    sie_all = measured[measured["method"] == "semi-implicit Euler"]
    early = sie_all[(sie_all["ratio"] < 0.7) & (sie_all["k"] >= 1000)]
    if len(early):
        r0 = early.iloc[0]
        rk4 = measured[(measured["method"] == "RK4") & measured["k"].isin(early["k"])]["ratio"].dropna()
        out.append(f"Semi-implicit Euler does not stay stable up to its linear limit 2/omega while the pendulum "
                   f"swings: at k = {', '.join(f'{k:g}' for k in early['k'])} N/m the spring's oscillation grows "
                   f"more than {G:g}-fold already at {early['ratio'].min():.2f}-{early['ratio'].max():.2f} x 2/omega "
                   f"(k = {r0['k']:g}: stable to {r0['h_stable']:.3g} s, blow-up at {_fmt(r0['h_blowup'])} s): the "
                   "swing's energy leaks into the spring (the swing dies down while the spring's oscillation grows). "
                   "The likely cause: the scheme takes the coupling terms, Coriolis -2 l' psi' / L and centrifugal "
                   "L psi'^2, explicitly and, the mass matrix depending on l, is not symplectic in these coordinates"
                   + (f"; RK4 at the same k keeps {rk4.min():.2f}-{rk4.max():.2f} of its theory." if len(rk4) else "."))
    pairs, exceptions = [], []
    for mj_method in ("mujoco:Euler", "mujoco:implicitfast", "mujoco:RK4"):
        textbook = FAMILY[mj_method]
        a = measured[measured["method"] == mj_method].set_index("k")
        b = measured[measured["method"] == textbook].set_index("k")
        common = a.index.intersection(b.index)
        if not len(common):
            continue
        pairs.append(f"{mj_method} = {textbook}")
        for column, what in (("h_stable", "stable step"), ("h_blowup", "blow-up step")):
            rel = (a.loc[common, column] / b.loc[common, column] - 1).dropna()
            exceptions += [f"{mj_method}'s {what} at k = {k:g} N/m ({100 * x:+.0f} %)" for k, x in rel.items()
                           if abs(x) > 1e-9]
    if pairs:
        out.append("MuJoCo's integrators fail where the textbook schemes do (" + ", ".join(pairs) + "), to the step"
                   + (", except " + ", ".join(exceptions) + " (where the swing's energy leaks into the spring, the "
                      "tiny difference of MuJoCo's base, driven through a large armature rather than prescribed, "
                      "decides when |l| passes the bound)" if exceptions else " at every k")
                   + ". Its Euler updates the velocity first (semi-implicit), and implicitfast is implicit only in "
                   "velocity-dependent forces (damping), not in the spring's stiffness: neither helps with a stiff "
                   "spring.")
    out.append(f"Physical runaway: the spin softens the spring to k/m - Omega^2 sin^2 psi; the relative equilibrium "
               f"moves out to l -> infinity as k falls to k_crit = m Omega^2 = {m:g} x {omega_base:.4g}^2 = "
               f"{k_crit:.4g} N/m, and below it the spring cannot hold the particle: l grows like "
               f"exp(sqrt(Omega^2 - k/m) t) for the exact solution (DOP853) and every method alike, whatever the step.")
    if crit["lo"] is not None:
        out.append(f"Numerically (the exact solution over the book's {case.initial[2]:g} s, runaway = |l| beyond "
                   f"{settings['escape']:g} m): it runs away at k = {crit['lo']:.4g} N/m and stays bounded at "
                   f"{crit['hi']:.4g} N/m, against k_crit = {k_crit:.4g} N/m from theory "
                   f"({(0.5 * (crit['lo'] + crit['hi']) / k_crit - 1) * 100:+.1f} %: just above k_crit the bounded "
                   "motion itself swings out beyond the bound).")
    runaway = data[(data["status"] == "physical runaway") & (data["method"] != "exact (DOP853)")]
    if len(runaway):
        gaps = (runaway["t_fail"] - runaway["t_exact"]).abs().dropna()
        out.append(f"Below k_crit ({', '.join(f'{k:g}' for k in sorted(set(runaway['k'])))} N/m) every method runs "
                   f"away together with the exact solution (escape times within {gaps.max():.2g} s of the exact "
                   "one, at steps far inside every limit): not a numerical instability, and no smaller step cures it.")
    if listing:
        out.append(f"The book's Matlab listing integrates with explicit Euler at dt = {listing['dt']:.3g} s over "
                   f"{listing['t_end']:.3g} s at k = {case.params['k']:g} N/m (omega = {listing['omega']:.4g} rad/s): "
                   f"a free spring oscillation grows by exp(omega^2 dt t / 2) = {listing['whole_run']:.2f} over the "
                   f"run. Its l(t) strays from the exact one by up to {listing['l_error']:.3g} m (the exact l spans "
                   f"{listing['l_range']:.3g} m), and over the last sixth its l'' has {listing['acc_ratio']:.2f} times "
                   "the exact RMS: the listing's figure of l(t) is drawn with a growing integration error.")
    return out


# == 2. double pendulum: Lyapunov exponent and agreement horizon =================================

def _scale(case):
    """Weights of the state (angles, rates) in the distance: rates divided by sqrt(g / l1)."""
    n = len(case.coords)
    w0 = math.sqrt(case.params["g"] / case.params.get("l1", 1.0))
    return np.concatenate([np.ones(n), np.full(n, 1.0 / w0)])


def _copies_rhs(model, n, copies):
    def rhs(t, y):
        out = np.empty_like(y)
        for c in range(copies):
            s = y[c * 2 * n:(c + 1) * 2 * n]
            out[c * 2 * n:c * 2 * n + n] = s[n:]
            out[c * 2 * n + n:(c + 1) * 2 * n] = model.accelerations(t, s[:n], s[n:])
        return out
    return rhs


def benettin(case, q0, v0, horizon, renormalise, d0, rtol):
    """Largest finite-time Lyapunov exponent by two neighbouring trajectories (Benettin): the neighbour
    is pulled back to distance d0 every `renormalise` seconds and the logarithms of the stretches are
    summed.  Returns times and ln(stretch) accumulated (lambda(t) = that / t)."""
    model = case.model("reference")
    n = len(case.coords)
    scale = _scale(case)
    x = np.concatenate([q0, v0]).astype(float)
    u = np.ones(2 * n) / scale
    u *= d0 / np.linalg.norm(u * scale)
    y = np.concatenate([x, x + u])
    rhs = _copies_rhs(model, n, 2)
    steps = int(round(horizon / renormalise))
    times, logs, total = [0.0], [0.0], 0.0
    for i in range(steps):
        sol = solve_ivp(rhs, (i * renormalise, (i + 1) * renormalise), y, method="DOP853", rtol=rtol,
                        atol=rtol * 1e-2)
        if sol.status != 0 or not np.all(np.isfinite(sol.y)):
            raise Unstable("DOP853", sol.t[-1], i, sol.message)
        y = sol.y[:, -1].copy()
        dx = y[2 * n:] - y[:2 * n]
        dist = np.linalg.norm(dx * scale)
        total += math.log(dist / d0)
        y[2 * n:] = y[:2 * n] + dx * (d0 / dist)
        times.append((i + 1) * renormalise)
        logs.append(total)
    return np.array(times), np.array(logs)


def amplification(case, horizon, rtol, delta=1e-7, points=200):
    """The largest singular value of the state-transition matrix along the book's initial conditions,
    by finite differences (one neighbour per state direction, in the scaled state), at `points` times."""
    model = case.model("reference")
    n = len(case.coords)
    scale = _scale(case)
    q0, v0, _ = case.initial
    x = np.concatenate([q0, v0]).astype(float)
    y0 = np.concatenate([x] + [x + delta * e / scale for e in np.eye(2 * n)])
    grid = np.linspace(0.0, horizon, points + 1)
    sol = solve_ivp(_copies_rhs(model, n, 2 * n + 1), (0.0, horizon), y0, method="DOP853", rtol=rtol,
                    atol=rtol * 1e-2, t_eval=grid)
    if sol.status != 0:
        raise Unstable("DOP853", sol.t[-1], len(sol.t), sol.message)
    y = sol.y.reshape(2 * n + 1, 2 * n, -1)
    phi = (y[1:] - y[0]) * scale[None, :, None] / delta  # [direction, component, time]
    sigma = np.array([np.linalg.svd(phi[:, :, i], compute_uv=False)[0] for i in range(phi.shape[2])])
    return sol.t, sigma


def agreement_horizon(case):
    """How long two sources can be expected to agree: (horizon in s, details).

    Two sources that integrate the same motion differ by about eps0 (the integrators' error level,
    relative, [stability.lyapunov] eps0) early on; a difference grows with the motion's sensitivity
    to its initial state, the largest singular value sigma(t) of the state-transition matrix along the
    book's initial conditions.  The horizon is the first t with eps0 sigma(t) = tol (the difference
    beyond which a trajectory comparison tests the chaos, not the equations).  If that lies beyond the
    case's horizon t_end, it is extrapolated with the finite-time exponent ln sigma(t_end) / t_end
    (an overestimate of the growth for a regular motion, so the horizon is on the safe side).
    A case without [stability.lyapunov] has no limit: (inf, {...})."""
    t_end = case.initial[2]
    spec = case.spec.get("stability", {}).get("lyapunov")
    if spec is None:
        return math.inf, {"t_end": t_end, "within": True,
                          "sentence": "no agreement horizon: the case declares no [stability.lyapunov]"}
    s = _settings(case, "lyapunov")
    eps0, tol = s["eps0"], s["tol"]
    start = time.perf_counter()
    result, fail = attempt(lambda: amplification(case, t_end, s["check_rtol"], delta=1e-6))
    if fail is not None:
        return t_end, {"t_end": t_end, "within": True, "eps0": eps0, "tol": tol,
                       "sentence": f"amplification not computed ({describe(fail)}); the case's horizon is kept"}
    t, sigma = result
    ftle = math.log(sigma[-1]) / t_end
    reached = np.nonzero(eps0 * sigma >= tol)[0]
    if reached.size:
        i = reached[0]
        horizon = float(t[i])
    else:
        horizon = t_end + (math.log(tol / (eps0 * sigma[-1])) / ftle if ftle > 0 else math.inf)
    within = horizon >= t_end
    sentence = (f"a difference of {eps0:g} grows by {sigma[-1]:.3g} over the case's {t_end:g} s (finite-time "
                f"exponent {ftle:.3g} 1/s), to {eps0 * sigma[-1]:.2g}; it reaches {tol:g} at "
                + (f"t = {horizon:.3g} s" if math.isfinite(horizon) else "no time")
                + (f": the case's {t_end:g} s lie within the agreement horizon" if within
                   else f": sources can be compared only up to {horizon:.3g} s"))
    return horizon, {"t_end": t_end, "within": within, "eps0": eps0, "tol": tol, "amplification": float(sigma[-1]),
                     "ftle": ftle, "horizon": horizon, "wall": time.perf_counter() - start, "sentence": sentence}


def lyapunov(case, settings, progress=None):
    start = time.perf_counter()
    starts = settings["initial"]
    rows, curves = [], {}
    eps0, tol = settings["eps0"], settings["tol"]
    for item in starts:
        label = item["label"]
        if progress:
            progress(f"Lyapunov exponent, {label}")
        q0 = np.array([case.value(x) for x in item["q"]])
        v0 = np.array([case.value(x) for x in item["v"]])
        out, fail = attempt(lambda: benettin(case, q0, v0, settings["horizon"], settings["renormalise"],
                                             settings["d0"], settings["rtol"]))
        if fail is not None:
            rows.append({"initial": label, "status": "unstable", "why": describe(fail)})
            continue
        t, logs = out
        curves[label] = (t, logs)
        lam = logs[-1] / t[-1]
        half = np.searchsorted(t, t[-1] / 2)
        lam_half = logs[half] / t[half]
        # Exponential growth: ln(stretch) rises linearly, and its second half adds about lambda T / 2.
        late = (logs[-1] - logs[half]) / (t[-1] - t[half])
        chaotic = late > 0.5 * lam and lam > 0.3
        running = logs[half:] / t[half:]
        rows.append({"initial": label, "q0": tuple(q0), "v0": tuple(v0), "status": "chaotic" if chaotic else "regular",
                     "lambda": lam, "lambda_half": lam_half, "lambda_second_half": late, "log_stretch": logs[-1],
                     "lambda_min": float(running.min()), "lambda_max": float(running.max()),
                     "horizon_rounding": math.log(tol / EPS) / lam if chaotic else None,
                     "horizon_integrators": math.log(tol / eps0) / lam if chaotic else None})
    data = pd.DataFrame(rows)
    check_h, details = agreement_horizon(case)
    table = pd.DataFrame([{
        "initial conditions": r["initial"],
        "motion": r["status"],
        f"lambda at {settings['horizon']:g} s [1/s]": _fmt(r.get("lambda")),
        f"lambda at {settings['horizon'] / 2:g} s [1/s]": _fmt(r.get("lambda_half")),
        f"agreement horizon, {eps0:g} -> {tol:g} [s]": (_fmt(r.get("horizon_integrators"), ".3g")
                                                       if r.get("horizon_integrators") else
                                                       f"> {settings['horizon']:g} (no exponential growth)"),
        "lambda over the second half [1/s]": (f"{r['lambda_min']:.3g}-{r['lambda_max']:.3g}"
                                               if r.get("lambda_min") is not None else "-"),
        f"agreement horizon, rounding {EPS:.1e} -> {tol:g} [s]": (_fmt(r.get("horizon_rounding"), ".3g")
                                                                 if r.get("horizon_rounding")
                                                                 else f"> {settings['horizon']:g}"),
    } for r in rows])
    findings = [f"Largest Lyapunov exponent by two neighbouring trajectories (Benettin; DOP853 at rtol "
                f"{settings['rtol']:g}, distance {settings['d0']:g} in the state with rates divided by sqrt(g/l1), "
                f"renormalised every {settings['renormalise']:g} s) over {settings['horizon']:g} s. The agreement "
                f"horizon T = ln(tol/eps0)/lambda is how long two sources that differ by eps0 stay within tol."]
    for r in rows:
        if r["status"] == "unstable":
            findings.append(f"{r['initial']}: {r['why']}.")
        elif r["status"] == "chaotic":
            findings.append(f"{r['initial']}: chaotic, lambda = {r['lambda']:.3g} 1/s (between "
                            f"{r['lambda_min']:.3g} and {r['lambda_max']:.3g} over the second half of the run): a "
                            f"difference grows e-fold every {1 / r['lambda']:.2g} s; from "
                            f"the integrators' {eps0:g} to {tol:g} in {r['horizon_integrators']:.2g} s, from rounding "
                            f"({EPS:.1e}) in {r['horizon_rounding']:.2g} s.")
        else:
            findings.append(f"{r['initial']}: regular (quasi-periodic): ln(stretch) grows only "
                            f"{r['log_stretch']:.3g} in {settings['horizon']:g} s and lambda(t) keeps falling "
                            f"({r['lambda_half']:.3g} at {settings['horizon'] / 2:g} s, {r['lambda']:.3g} at "
                            f"{settings['horizon']:g} s, like ln(t)/t): no positive exponent, errors grow "
                            "algebraically and two sources agree for far longer than the case's horizon.")
    findings.append(f"Trajectory check (the book's initial conditions, reference, finite-time amplification): "
                    f"{details['sentence']}.")
    series = {"curves": curves, "rows": data, "check": details, "horizon": settings["horizon"]}
    return _result(case, "lyapunov", "Lyapunov exponent and the agreement horizon", settings, data, table,
                   findings, series, start)


def energy_drift(case, settings, progress=None):
    """Each method over a long horizon at one step: |E(t) - E(0)| relative to the swing's energy above rest."""
    start = time.perf_counter()
    q0, v0, _ = case.initial
    T, dt = settings["horizon"], settings["dt"]
    every = max(1, int(round(settings["output_step"] / dt)))
    reference = case.model("reference")
    rest = reference.energy(0.0, np.zeros(len(q0)), np.zeros(len(v0)))
    e0 = reference.energy(0.0, q0, v0)
    swing = e0 - rest
    rows, curves = [], {}
    for method in settings["methods"]:
        if progress:
            progress(f"energy drift, {method}")
        source = "mujoco" if method in MUJOCO_METHODS else "reference"
        kwargs = {"rtol": settings["rtol"]} if method in SCIPY_METHODS else {"dt": dt}
        run, fail = attempt(lambda: simulate(case.model(source), (q0, v0), T, method, output_step=every * dt,
                                             work=False, **kwargs))
        label = method + (f" (rtol {settings['rtol']:g})" if method in SCIPY_METHODS else "")
        if fail is not None:
            rows.append({"method": label, "status": "unstable", "t_fail": fail["t"], "step_fail": fail["step"],
                         "why": fail["why"]})
            continue
        t = run.index.to_numpy()
        drift = np.abs(run["energy"].to_numpy() - e0) / swing
        curves[label] = (t, drift)
        at = lambda s: float(np.max(drift[t <= s]))
        # Character: how the envelope max |dE| over [t/2, t] grows from t = T/10 to T.
        env = lambda s: float(np.max(drift[(t >= s / 2) & (t <= s)]))
        exponent = math.log(env(T) / env(T / 10)) / math.log(10) if env(T / 10) > 0 else None
        final = float(np.mean(drift[t >= 0.9 * T]))
        sign = float(np.mean(run["energy"].to_numpy()[t >= 0.9 * T] - e0))
        if at(T) > 1.0:
            character = f"gains {at(T):.3g} times the swing's energy"
        elif exponent is not None and exponent > 0.5:
            character = "secular " + ("loss" if sign < 0 else "gain")
        elif exponent is not None and exponent < 0.2:
            character = "bounded"
        else:
            character = "slow growth"
        rows.append({"method": label, "status": "ran", "dt": dt if method not in SCIPY_METHODS else None,
                     "evaluations": run.attrs["evaluations"], "wall": run.attrs["wall"],
                     "drift_1s": at(1.0), "drift_T10": at(T / 10), "drift_T": at(T), "final_mean": final,
                     "final_sign": "loses" if sign < 0 else "gains", "growth_exponent": exponent,
                     "character": character})
    data = pd.DataFrame(rows)
    table = pd.DataFrame([{
        "method": r["method"],
        "step": _fmt(r.get("dt")),
        "max |dE|/E_swing, 1 s": _fmt(r.get("drift_1s")),
        f"{T / 10:g} s": _fmt(r.get("drift_T10")),
        f"{T:g} s": _fmt(r.get("drift_T")),
        "growth exponent": _fmt(r.get("growth_exponent"), ".2f"),
        "character": r.get("character") if r["status"] == "ran" else describe({"status": "unstable", **r,
                                                                               "t": r.get("t_fail"),
                                                                               "step": r.get("step_fail")}),
    } for r in rows])
    dop = f", DOP853 at rtol {settings['rtol']:g}" if "DOP853" in settings["methods"] else ""
    findings = [f"From the book's initial conditions over {T:g} s at dt = {dt:g} s (the step of the book's Pascal "
                f"listing){dop}; "
                f"the error is |E(t) - E(0)| relative to the swing's energy above rest, E(0) - E_rest = {swing:.4g} J. "
                "The growth exponent is d ln(max |dE|) / d ln t from T/10 to T: 0 for a bounded error, 1 for a "
                "linear drift."]
    ran = data[data["status"] == "ran"] if "status" in data else data
    top = (reference.energy(0.0, np.array([math.pi, 0.0]), np.zeros(2)) - rest) / swing if len(q0) == 2 else None
    for _, r in ran.iterrows():
        text = (f"{r['method']}: {r['character']} (growth exponent {r['growth_exponent']:.2f}); "
                f"{r['drift_1s']:.2g} after 1 s, {r['drift_T10']:.2g} after {T / 10:g} s, {r['drift_T']:.2g} by {T:g} s")
        if r["drift_T"] > 1.0 and top:
            text += (f": the pendulum gains more than the {top:.3g} swing energies that lift both masses over the "
                     "top, and whirls")
        findings.append(text + ".")
    for _, r in (data[data["status"] == "unstable"].iterrows() if "status" in data else []):
        findings.append(f"{r['method']}: unstable at t = {_fmt(r['t_fail'])} s (step {r['step_fail']}): {r['why']}.")
    pairs = [("mujoco:Euler", "semi-implicit Euler"), ("mujoco:implicitfast", "semi-implicit Euler"),
             ("mujoco:RK4", "RK4")]
    same = []
    for a, b in pairs:
        if a in curves and b in curves and len(curves[a][1]) == len(curves[b][1]):
            same.append(f"{a} = {b} to {np.max(np.abs(curves[a][1] - curves[b][1])):.1g}")
    if same:
        findings.append("MuJoCo's integrators are the textbook schemes: " + "; ".join(same) + " (energy error curves).")
    sie = ran[ran["method"] == "semi-implicit Euler"]
    if len(sie):
        findings.append("Semi-implicit Euler is symplectic only for a separable Hamiltonian in (q, p); here it "
                        "steps the angles' rates through a configuration-dependent mass matrix, so it is not, yet its "
                        f"energy error stays bounded after the first swing ({sie['final_mean'].iloc[0]:.2g} of the "
                        "swing's energy on average over the last tenth): the energy it sheds in the first second "
                        "is the numerical damping that the book's figures show.")
    series = {"curves": curves, "rows": data, "swing": swing, "horizon": T, "dt": dt}
    return _result(case, "energy_drift", "Long-run energy error of each method", settings, data, table,
                   findings, series, start)


# == 3. spinning top: the Euler-angle singularity and the sleeping top ===========================

def _rot_exact(angles):
    """Rz(p) Rx(n) Rz(s) (world from body) in exact rational arithmetic from the doubles' sines and cosines."""
    c = [Fraction(float(np.cos(a))) for a in angles]
    s = [Fraction(float(np.sin(a))) for a in angles]
    rz = lambda i: [[c[i], -s[i], 0], [s[i], c[i], 0], [0, 0, 1]]
    rx = [[1, 0, 0], [0, c[1], -s[1]], [0, s[1], c[1]]]
    mul = lambda a, b: [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    return mul(mul(rz(0), rx), rz(2)), s, c


def _exact_rates(angles, omega):
    """Euler rates from the body's angular velocity, exactly (w = J rates, engines/euler.py's J)."""
    _, s, c = _rot_exact(angles)
    sn, cn, ss, cs = s[1], c[1], s[2], c[2]
    wx, wy, wz = (Fraction(float(w)) for w in omega)
    norm = ss * ss + cs * cs
    dp = (ss * wx + cs * wy) / (sn * norm)
    dn = (cs * wx - ss * wy) / norm
    return [dp, dn, wz - cn * dp]


def _exact_angular_acceleration(angles, rates, accelerations):
    """The body's angular acceleration J q'' + J' q' (engines/euler.py), exactly, from double rates and accelerations."""
    _, s, c = _rot_exact(angles)
    sn, cn, ss, cs = s[1], c[1], s[2], c[2]
    dp, dn, ds = (Fraction(float(x)) for x in rates)
    ap, an, as_ = (Fraction(float(x)) for x in accelerations)
    jq = [ss * sn * ap + cs * an, cs * sn * ap - ss * an, cn * ap + as_]
    bias = [-ss * ds * dn + (cs * ds * sn + ss * cn * dn) * dp,
            -cs * ds * dn + (-ss * ds * sn + cs * cn * dn) * dp,
            -sn * dn * dp]
    return [a + b for a, b in zip(jq, bias)]


def _exact_euler_equations(case, angles, omega):
    """The true angular acceleration in the body frame: I_O w' = M_O - w x I_O w, I_O = diag(Ixx, Ixx, Izz),
    M_O = (0, 0, h) x (weight in the body frame) + (0, 0, Mz); exact rational arithmetic."""
    p = {k: Fraction(float(v)) for k, v in case.params.items()}
    rot, _, _ = _rot_exact(angles)
    weight = [rot[2][i] * (-p["m"] * p["g"]) for i in range(3)]  # R^T (0, 0, -m g)
    moment = [-p["h"] * weight[1], p["h"] * weight[0], p["Mz"]]
    w = [Fraction(float(x)) for x in omega]
    inertia = [p["Ixx"], p["Ixx"], p["Izz"]]
    iw = [inertia[i] * w[i] for i in range(3)]
    gyro = [w[1] * iw[2] - w[2] * iw[1], w[2] * iw[0] - w[0] * iw[2], w[0] * iw[1] - w[1] * iw[0]]
    return [(moment[i] - gyro[i]) / inertia[i] for i in range(3)]


def _native_angular_acceleration(model, angles, omega):
    """An engine's own answer for a ball joint in quaternion form: body angular acceleration from
    (quaternion, body angular velocity), without the adapters' Euler-angle maps."""
    from engines import euler
    quaternion = euler.quaternion(angles)
    kind = type(model).__name__
    if kind == "MujocoModel":
        import mujoco
        (_, (qadr, dof), _), = [entry for entry in model.layout if entry[0] == "euler"]
        d = model.d
        d.qpos[qadr:qadr + 4] = quaternion
        d.qvel[dof:dof + 3] = omega
        d.qfrc_applied[:] = model.applied
        mujoco.mj_forward(model.m, d)
        return d.qacc[dof:dof + 3].copy()
    if kind == "PinocchioModel":
        import pinocchio as pin
        (_, joint, _), = [entry for entry in model.layout if entry[0] == "euler"]
        config = pin.neutral(model.m)
        config[joint.idx_q:joint.idx_q + 4] = np.roll(quaternion, -1)  # (x, y, z, w)
        velocity = np.zeros(model.m.nv)
        velocity[joint.idx_v:joint.idx_v + 3] = omega
        acc = pin.aba(model.m, model.d, config, velocity, model.applied.copy())
        return np.asarray(acc[joint.idx_v:joint.idx_v + 3]).copy()
    raise ValueError(f"no native ball-joint evaluation for {kind}")


def euler_singularity(case, settings, progress=None):
    start = time.perf_counter()
    variant = _variant(case, **settings.get("overrides", {}))
    reference = variant.model("reference")
    engines = {"mujoco": variant.model("mujoco"), "pinocchio": variant.model("pinocchio")}
    spin, transverse = settings["spin"], settings["transverse"]
    chi = settings["direction"]
    omega = np.array([transverse * math.cos(chi), transverse * math.sin(chi), spin])
    rows = []
    for n in settings["nutation"]:
        angles = np.array([settings["precession"], n, settings["spin_angle"]])
        truth = _exact_euler_equations(variant, angles, omega)
        size = math.sqrt(float(sum(x * x for x in truth)))
        err = lambda vec: math.sqrt(float(sum((Fraction(float(a)) - b) ** 2 for a, b in zip(vec, truth)))) / size
        rates_exact = _exact_rates(angles, omega)
        rates = np.array([float(x) for x in rates_exact])
        acc, fail = attempt(lambda: reference.accelerations(0.0, angles, rates))
        base = {"nutation": n, "true_size": size, "precession_rate": rates[0], "spin_rate": rates[2]}
        if fail is None and np.all(np.isfinite(acc)):
            rows.append({**base, "source": "reference (Euler angles)", "status": "ok",
                         "error": err(_exact_angular_acceleration(angles, rates, acc))})
        else:
            rows.append({**base, "source": "reference (Euler angles)", "status": "not finite", "error": None})
        # The part of that error that the Euler rates' rounding alone makes (the state, not the equations).
        omega_rounded = [float(x) for x in _exact_angular_velocity(angles, rates)]
        rows.append({**base, "source": "truth at the rounded Euler rates", "status": "ok",
                     "error": err([float(x) for x in _exact_euler_equations(variant, angles, omega_rounded)])})
        for name, model in engines.items():
            rows.append({**base, "source": f"{name} (quaternion)", "status": "ok",
                         "error": err(_native_angular_acceleration(model, angles, omega))})
    data = pd.DataFrame(rows)

    # A motion through the near-upright: the axis swings through the vertical, missing it by `miss`.
    passes = _passages(variant, settings, progress)
    data_pass = pd.DataFrame([
        {"miss": r["miss"], "closest": r.get("closest"), "precession_rate": r["precession_rate"],
         "integrator": label, "status": x.get("status", r["status"]),
         **{k: x.get(k) for k in ("before", "after", "max", "evaluations")},
         "t_fail": x.get("fail", {}).get("t"), "step_fail": x.get("fail", {}).get("step")}
        for r in passes for label, x in (("Euler angles, DOP853", r.get("dop853", {})),
                                         ("Euler angles, RK4 fixed step", r.get("rk4", {})),
                                         ("MuJoCo RK4 vs half step", {"status": "ok", "max": r.get("mujoco_estimate")}))])

    ref = data[data["source"] == "reference (Euler angles)"]
    table = pd.DataFrame([{
        "nutation [rad]": f"{n:.0e}",
        "precession rate [rad/s]": f"{grp['precession_rate'].iloc[0]:.3g}",
        **{src: _fmt(grp[grp["source"] == src]["error"].iloc[0], ".2e", none="not finite")
           for src in ("reference (Euler angles)", "truth at the rounded Euler rates", "mujoco (quaternion)",
                       "pinocchio (quaternion)")}} for n, grp in data.groupby("nutation", sort=False)])
    ok = ref.dropna(subset=["error"])
    slope = (np.polyfit(np.log(ok["nutation"]), np.log(ok["error"]), 1)[0]
             if len(ok[ok["error"] > 1e-14]) >= 3 else None)
    engines_worst = data[data["source"].str.contains("quaternion")]["error"].max()
    findings = [
        f"The book's Euler-angle equations divide by sin(nutation): at nutation n the precession rate of a given "
        f"physical motion is w_perp / sin n (here w_perp = {transverse:g} rad/s across the axis, spin "
        f"{spin:.4g} rad/s), and the equations cancel terms of size ~ 1/n^2 to give an angular acceleration of "
        f"size ~ {ref['true_size'].median():.3g} rad/s^2. Compared is the body's angular acceleration, which has "
        "no singularity, against Euler's equations in the body frame evaluated exactly (rational arithmetic).",
        "Relative error of the Euler-angle reference: " + ", ".join(
            f"{_fmt(r['error'], '.1e', 'not finite')} at n = {r['nutation']:.0e}" for _, r in ref.iterrows())
        + (f" (slope {slope:.2f} in log-log: error ~ eps / n^{-slope:.1f})" if slope is not None else "") + ".",
        f"MuJoCo and Pinocchio, fed the same state as a quaternion and a body angular velocity, stay at "
        f"{engines_worst:.1e} or better at every nutation: their formulation has no singularity."]
    rounding = data[data["source"] == "truth at the rounded Euler rates"]
    worst_i = ref["error"].astype(float).idxmax() if ref["error"].notna().any() else None
    if worst_i is not None:
        n_worst, total = ref.loc[worst_i, "nutation"], ref.loc[worst_i, "error"]
        part = rounding[rounding["nutation"] == n_worst]["error"].iloc[0]
        findings.append(
            f"At n = {n_worst:.0e}, rounding the Euler rates to doubles alone (the true acceleration at the rounded "
            f"state) accounts for {part:.1e} of the {total:.1e}: " +
            ("the digits are lost in evaluating the equations, whose terms of size ~1/n^2 cancel, not in "
             "representing the state." if part < 0.1 * total else
             "the coordinates themselves, not only the equations, lose the digits."))
    for r in passes:
        if r["status"] != "ok":
            findings.append(f"Passage with miss {r['miss']:.0e} rad: MuJoCo {describe(r['fail'])}.")
            continue
        parts = []
        for key, label in (("dop853", f"adaptive DOP853 (rtol {settings['rtol']:g})"),
                           ("rk4", f"fixed-step RK4 at dt = {settings['mujoco_step']:g} s")):
            x = r.get(key, {})
            if x.get("status") == "ok":
                parts.append(f"{label} misses the axis by {x['before']:.1e} rad before the first passage and "
                             f"{x['after']:.1e} after the last ({x['evaluations']} evaluations)")
            elif x:
                parts.append(f"{label}: {describe(x['fail'])}")
        findings.append(f"Trajectory through the near-upright (spin {r['spin']:.3g} rad/s, {r['passages']} passages "
                        f"in {settings['passage_horizon']:g} s, closest {r['closest']:.1e} rad): in Euler angles "
                        + "; ".join(parts) + f". MuJoCo's quaternion RK4 at the same step stays within "
                        f"{r['mujoco_estimate']:.1e} rad of its half-step twin.")
    ok = [r for r in passes if r["status"] == "ok" and r.get("dop853", {}).get("status") == "ok"]
    if len(ok) >= 2:
        findings.append(f"An adaptive integrator follows the Euler-angle singularity by shrinking its steps: its "
                        f"evaluations grow from {ok[0]['dop853']['evaluations']} (closest {ok[0]['closest']:.0e} rad) "
                        f"to {ok[-1]['dop853']['evaluations']} (closest {ok[-1]['closest']:.0e} rad), as the "
                        f"precession rate peaks near w_perp / closest; a fixed step cannot.")
    series = {"rows": data, "passes": passes}
    out = _result(case, "euler_singularity", "The Euler-angle singularity at zero nutation", settings, data, table,
                  findings, series, start)
    out["data_passages"] = data_pass
    return out


def _exact_angular_velocity(angles, rates):
    _, s, c = _rot_exact(angles)
    sn, cn, ss, cs = s[1], c[1], s[2], c[2]
    dp, dn, ds = (Fraction(float(x)) for x in rates)
    return [ss * sn * dp + cs * dn, cs * sn * dp - ss * dn, cn * dp + ds]


def _mujoco_tilt(model, q0, v0, t_end, dt):
    """MuJoCo's own RK4 from the book's state (q0, v0): times and the axis tilt (x, y components of the
    symmetry axis R e_z, from the quaternion: exact near upright, where Euler angles are not)."""
    import mujoco
    import mujoco.rollout
    (_, (qadr, _), _), = [entry for entry in model.layout if entry[0] == "euler"]
    m, d, state0, forces = model.stepping(q0, v0, dt, "RK4")  # the scene as MuJoCo steps it
    steps = int(round(t_end / dt))
    states, _ = mujoco.rollout.rollout(m, d, state0[None], forces[None, None], nstep=steps,
                                       control_spec=mujoco.mjtState.mjSTATE_QFRC_APPLIED)
    quats = np.concatenate([state0[None], states[0]])[:, 1 + qadr:1 + qadr + 4]
    if not np.all(np.isfinite(quats)):
        raise Unstable("mujoco:RK4", t_end, steps, "state is not finite")
    w, x, y, z = quats.T
    return np.arange(steps + 1) * dt, np.column_stack([2 * (x * z + w * y), 2 * (y * z - w * x)])


def _closest(tilt):
    """Closest approach of the axis to the vertical along a sampled path: the least distance from the
    origin to the segments between consecutive tilts (a passage lasts less than a step)."""
    a, b = tilt[:-1], tilt[1:]
    d = b - a
    s = np.clip(-np.einsum("ij,ij->i", a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300), 0.0, 1.0)
    return float(np.min(np.linalg.norm(a + s[:, None] * d, axis=1)))


def _passages(case, settings, progress):
    """Reference (Euler angles, DOP853) and MuJoCo (quaternion, RK4) through near-upright passages.

    Linearised about the upright, the axis tilt xi = x + i y obeys Ixx xi'' - i Izz S xi' - m g h xi = 0
    (S the spin about the axis): two circular motions at Omega0 +- mu, Omega0 = Izz S / (2 Ixx),
    mu = Izz sqrt(S^2 - S_c^2) / (2 Ixx).  Started at tilt n0 and precessing at p' = Omega0 + mu d / n0,
    the two have amplitudes differing by d: the axis swings through the vertical every pi / mu, missing
    it by d.  The nonlinear motion shifts the rate that aims through the vertical: it is found with
    MuJoCo (the least closest approach over the first passage), and the miss d added to it."""
    from scipy.optimize import minimize_scalar

    p = case.params
    spin, n0, T = settings["passage_spin"], settings["start_nutation"], settings["passage_horizon"]
    s_c = 2 * math.sqrt(p["Ixx"] * p["m"] * p["g"] * p["h"]) / p["Izz"]
    omega0 = p["Izz"] * spin / (2 * p["Ixx"])
    mu = p["Izz"] * math.sqrt(spin**2 - s_c**2) / (2 * p["Ixx"])
    dt = settings["mujoco_step"]
    every = max(1, int(round(settings["passage_output"] / dt)))
    model = case.model("mujoco")
    state = lambda rate: (np.array([0.0, n0, 0.0]), np.array([rate, 0.0, spin - rate * math.cos(n0)]))
    first = math.pi / mu  # the first passage lies within half a nutation period
    aim = minimize_scalar(lambda rate: _closest(_mujoco_tilt(model, *state(rate), first, dt)[1]),
                          bracket=(omega0 - 0.05 * mu, omega0, omega0 + 0.05 * mu), tol=1e-12)
    out = []
    for miss in settings["miss"]:
        if progress:
            progress(f"Euler singularity, passage {miss:g} rad")
        rate = aim.x + mu * miss / n0
        q0, v0 = state(rate)
        row = {"miss": miss, "spin": spin, "start_nutation": n0, "precession_rate": rate}
        mj, fail = attempt(lambda: [_mujoco_tilt(model, q0, v0, T, h) for h in (dt, dt / 2)])
        if fail is not None:
            out.append({**row, "status": "mujoco unstable", "fail": fail})
            continue
        (t, tilt), (_, twin) = mj
        t, tilt, twin = t[::every], tilt, twin[::2 * every]
        row.update({"closest": _closest(tilt), "t": t, "nutation": np.linalg.norm(tilt[::every], axis=1)})
        tilt = tilt[::every]
        row["error_mj"] = np.linalg.norm(tilt - twin, axis=1)
        row["mujoco_estimate"] = float(row["error_mj"].max())
        near = np.nonzero(row["nutation"] < 0.2 * n0)[0]
        first_i, last_i = (near[0], near[-1]) if near.size else (len(t) // 2, len(t) // 2)
        row["passages"] = int(np.sum(np.diff((row["nutation"] < 0.2 * n0).astype(int)) == 1))
        # The Euler-angle reference: adaptive DOP853, and fixed-step RK4 at MuJoCo's step.
        for key, kwargs in (("dop853", {"method": "DOP853", "rtol": settings["rtol"]}),
                            ("rk4", {"method": "RK4", "dt": dt})):
            ref, fail = attempt(lambda: simulate(case.model("reference"), (q0, v0), T, output_step=every * dt,
                                                 work=False, **kwargs))
            if fail is not None:
                row[key] = {"status": "unstable", "fail": fail}
                continue
            n, pr = ref["nutation"].to_numpy(), ref["precession"].to_numpy()
            ref_tilt = np.column_stack([np.sin(n) * np.sin(pr), -np.sin(n) * np.cos(pr)])
            err = np.linalg.norm(ref_tilt - tilt, axis=1)
            if not np.all(np.isfinite(err)):
                bad = int(np.argmin(np.isfinite(err)))
                row[key] = {"status": "unstable", "fail": {"status": "unstable", "t": float(t[bad]), "step": bad * every,
                                                          "why": "state is not finite"}}
                continue
            row[key] = {"status": "ok", "error": err, "before": float(err[:max(first_i, 1)].max()),
                        "after": float(err[last_i:].max()), "max": float(err.max()),
                        "evaluations": ref.attrs["evaluations"]}
        row["status"] = "ok"
        out.append(row)
    return out


def sleeping_top(case, settings, progress=None):
    """The least spin of a stable upright top, by bisection with MuJoCo (quaternions: no singularity upright)."""
    start = time.perf_counter()
    variant = _variant(case, **settings.get("overrides", {}))
    p = variant.params
    criterion = 2 * math.sqrt(p["Ixx"] * p["m"] * p["g"] * p["h"]) / p["Izz"]
    n0, bound, T = settings["start_nutation"], settings["bound"], settings["horizon"]
    dt, method = settings["mujoco_step"], settings.get("method", "mujoco:RK4")
    model = variant.model("mujoco")
    trail = []

    def stays_up(s):
        run, fail = attempt(lambda: simulate(model, (np.array([0.0, n0, 0.0]), np.array([0.0, 0.0, s])), T, method,
                                             dt=dt, output_step=dt * max(1, int(round(0.01 / dt))), work=False))
        if fail is not None:
            trail.append({"spin": s, "stable": False, "max_nutation": None, "status": "unstable", "why": describe(fail)})
            return False
        top = float(run["nutation"].max())
        over = np.nonzero(run["nutation"].to_numpy() > bound)[0]
        trail.append({"spin": s, "stable": top <= bound, "max_nutation": top, "status": "ran",
                      "t_fall": float(run.index[over[0]]) if over.size else None})
        return top <= bound

    if progress:
        progress("sleeping top")
    lo, hi = settings["bracket"][0] * criterion, settings["bracket"][1] * criterion
    bracket_ok = not stays_up(lo) and stays_up(hi)
    while bracket_ok and hi - lo > settings["resolution"] * criterion:
        mid = 0.5 * (lo + hi)
        if stays_up(mid):
            hi = mid
        else:
            lo = mid
    # The exact motion's first integrals at this bound and horizon (`top_nutation`): the spin the bisection
    # should find.  Below it the top reaches the bound within T.
    falls = lambda s: top_nutation(p, s, n0, T)[0] >= bound
    f_lo, f_hi = 0.5 * criterion, 1.5 * criterion
    while f_hi - f_lo > 1e-7 * criterion:
        mid = 0.5 * (f_lo + f_hi)
        f_lo, f_hi = (mid, f_hi) if falls(mid) else (f_lo, mid)
    finite = 0.5 * (f_lo + f_hi)
    turning = top_nutation(p, finite, n0, math.inf)
    data = pd.DataFrame(trail).assign(criterion=criterion, finite_horizon=finite)
    summary = pd.DataFrame([{"quantity": "criterion s_c = 2 sqrt(Ixx m g h) / Izz", "spin [rad/s]": f"{criterion:.6g}"},
                            {"quantity": f"first integrals: largest nutation within {T:g} s reaches {bound:g} rad "
                                         f"from {n0:g} rad below", "spin [rad/s]": f"{finite:.6g}"},
                            {"quantity": f"MuJoCo ({method}, dt = {dt:g} s): falls at", "spin [rad/s]":
                             f"{lo:.6g}" if bracket_ok else "bracket failed"},
                            {"quantity": "MuJoCo: stays up at", "spin [rad/s]": f"{hi:.6g}" if bracket_ok else "-"}])
    findings = [
        f"Upright (sleeping) top: spinning at s about its vertical axis, it is stable iff s^2 > 4 m g h Ixx / Izz^2 "
        f"(Maxwell and Klein; Ixx about the tip): s_c = 2 sqrt(Ixx m g h) / Izz = {criterion:.4g} rad/s "
        f"({criterion / (2 * math.pi):.3g} rev/s) for the book's top. The book states no such criterion; its "
        "parameter names are those of the formula (Ixx about the tip O, Izz about the axis).",
        f"Numerically (MuJoCo, {method} at dt = {dt:g} s, no resisting moment: Mz = 0 overrides the book's "
        f"{case.params.get('Mz', 0.0):g} N m, which slows every top until it falls): started {n0:g} rad from upright "
        f"with only the spin, the top counts as up if its nutation stays below {bound:g} rad for {T:g} s. "
        + (f"It falls at {lo:.6g} and stays up at {hi:.6g} rad/s (bisection to {settings['resolution']:.0e} of s_c): "
           f"{(lo / criterion - 1) * 100:+.2f} % to {(hi / criterion - 1) * 100:+.2f} % of the criterion."
           if bracket_ok else "The bracket around the criterion did not hold."),
        (f"Below s_c the upright is unstable (the tilt grows like exp(sigma t), sigma = Izz sqrt(s_c^2 - s^2) / "
         f"(2 Ixx)), but the exact motion only wobbles out to the turning point of its first integrals, "
         f"n_max ~ 2 sqrt(1 - s^2 / s_c^2), and back: a top {100 * (1 - finite / criterion):.2f} % below s_c "
         f"reaches {turning[1]:.3g} rad after {turning[2]:.3g} s. So with a bound of {bound:g} rad and {T:g} s the "
         f"first integrals put the threshold at {finite:.5g} rad/s ({(finite / criterion - 1) * 100:+.2f} % of s_c); "
         f"MuJoCo's bracket [{lo:.5g}, {hi:.5g}] "
         + ("contains it." if lo <= finite <= hi else
            f"misses it by {min(abs(finite - lo), abs(finite - hi)) / criterion * 100:.3f} % of s_c.")
         + " A smaller bound moves the measured threshold up to s_c (as s_c sqrt(1 - bound^2 / 4)).")
        if bracket_ok else "No comparison (the bracket failed)."]
    series = {"trail": data, "criterion": criterion, "finite": finite, "lo": lo, "hi": hi, "n0": n0, "bound": bound,
              "horizon": T, "params": p, "method": method, "dt": dt}
    return _result(case, "sleeping_top", "The sleeping top: least spin of a stable upright top", settings,
                   data, summary, findings, series, start)


def top_nutation(p, s, n0, T):
    """The heavy symmetric top (Mz = 0) started at nutation n0 with only its spin s about its axis: the
    largest nutation it reaches within T, and its turning point, from the first integrals (energy,
    vertical and axial angular momentum), exact for any amplitude.  With x = 1 - cos(nutation),
        x'^2 = (x - x0) G(x),   G(x) = beta (2 x - x^2) - a^2 (x - x0),   a = Izz s / Ixx, beta = 2 m g h / Ixx,
    so the nutation swings between x0 and the root x+ of G:
        x+ ~ a^2 x0 / (a^2 - 2 beta)        (a^2 > 2 beta, s > s_c: the top sleeps, n_max ~ n0 s / sqrt(s^2 - s_c^2))
        x+ ~ (2 beta - a^2) / beta          (s < s_c: it falls, but only to n_max ~ 2 sqrt(1 - s^2 / s_c^2)).
    The time to reach x is the integral of dx / sqrt((x - x0) G), with x = x0 + w^2 regular at x0.
    Returns (largest nutation within T, turning-point nutation, time to reach it)."""
    from scipy.integrate import quad
    a2 = (p["Izz"] * s / p["Ixx"]) ** 2
    beta = 2 * p["m"] * p["g"] * p["h"] / p["Ixx"]
    x0 = 2 * math.sin(n0 / 2) ** 2
    b = a2 - 2 * beta
    root = math.sqrt(b * b + 4 * beta * a2 * x0)
    x_plus = 2 * a2 * x0 / (b + root) if b > 0 else (root - b) / (2 * beta)
    x_plus = min(x_plus, 2.0)
    G = lambda x: beta * (2 * x - x * x) - a2 * (x - x0)
    time_to = lambda x: quad(lambda w: 2.0 / math.sqrt(max(G(x0 + w * w), 1e-300)), 0.0,
                             math.sqrt(max(x - x0, 0.0)), limit=200)[0]
    nutation = lambda x: 2 * math.asin(math.sqrt(min(x, 2.0) / 2))
    t_turn = time_to(x_plus)
    if t_turn <= T:
        return nutation(x_plus), nutation(x_plus), t_turn
    x_T = brentq(lambda x: time_to(x) - T, x0, x_plus, xtol=1e-16, rtol=1e-12)
    return nutation(x_T), nutation(x_plus), t_turn


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
        try:
            _settings(case, key)
        except ValueError as error:
            raise ValueError(f"{case.file}: stability.{key}: {error}") from None


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


def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


METHOD_STYLE = {
    "explicit Euler": dict(color="tab:red", marker="o"),
    "semi-implicit Euler": dict(color="tab:blue", marker="s"),
    "RK4": dict(color="tab:green", marker="^"),
    "DOP853": dict(color="black", marker="D"),
    "mujoco:Euler": dict(color="tab:cyan", marker="x"),
    "mujoco:implicitfast": dict(color="tab:purple", marker="+"),
    "mujoco:RK4": dict(color="tab:olive", marker="1"),
}


def _style(label):
    for key, style in METHOD_STYLE.items():
        if label.startswith(key) and (key != "RK4" or label == "RK4"):
            return dict(style)
    return {}


def figure_stable_step(result, path):
    plt = _plt()
    s = result["series"]
    rows, curves = s["rows"], s["curves"]
    measured = rows[rows["status"] == "measured"]
    kmin = min(rows["k"].min(), s["k_crit"]) / 1.5
    fig, axes = plt.subplots(1, 2, figsize=(14, 7.4), sharey=True)
    families = [("explicit Euler", "explicit Euler"), ("semi-implicit Euler", "semi-implicit Euler = MuJoCo Euler, implicitfast"),
                ("RK4", "RK4 = MuJoCo RK4")]
    offsets = {"mujoco:Euler": 1.06, "mujoco:implicitfast": 1.12, "mujoco:RK4": 1.06}
    panels = [(axes[0], "h_stable", "", f"largest stable step: the oscillation grows at most {s['growth']:g} x "
                                         f"over {0.75 * s['horizon']:g} s"),
              (axes[1], "h_blowup", " limit", "smallest blow-up step: |l| > escape bound, NaN or MuJoCo reset")]
    for ax, column, suffix, title in panels:
        for method, label in families:
            key = method + suffix
            if key in curves:
                theory = ("theory: growth %g x over %g s" % (s["growth"], 0.75 * s["horizon"]) if not suffix
                          else "theory: " + {"semi-implicit Euler": "2/omega", "RK4": "2 sqrt(2)/omega"}[method])
                ax.plot(curves["k"], curves[key], color=_style(method)["color"], lw=6, alpha=0.25,
                        label=f"{theory}, {label}", solid_capstyle="butt")
        for method, group in measured.groupby("method", sort=False):
            group = group.dropna(subset=[column])
            if group.empty:
                continue
            st = _style(method)
            filled = not method.startswith("mujoco")
            ax.plot(group["k"] * offsets.get(method, 1.0), group[column], ls="-" if filled else "none", lw=0.8,
                    ms=7 if filled else 10, marker=st["marker"], color=st["color"],
                    mfc=st["color"] if filled else "none", mew=1.6, label=f"measured, {method}")
        ax.axvspan(kmin, s["k_crit"], color="0.88", zorder=0)
        ax.axvline(s["k_crit"], color="0.3", ls="--", lw=1)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(kmin, rows["k"].max() * 1.6)
        ax.set_xlabel("spring stiffness k [N/m]")
        ax.set_title(title, fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    finite = [np.nanmin(curves[m]) for m, _ in families if m in curves]
    top = [np.nanmax(curves[m + " limit"]) for m, _ in families if m + " limit" in curves]
    ymin, ymax = min(finite) / 3, max(top) * 4
    axes[0].set_ylim(ymin, ymax)
    axes[0].set_ylabel("time step dt [s]")
    for ax in axes:
        ax.text(kmin * 1.15, math.sqrt(ymin * ymax), f"physical runaway:\nk < k_crit = m Omega^2\n= {s['k_crit']:.4g} N/m;"
                "\nthe exact solution\nescapes too,\nno step helps", ha="left", va="center", fontsize=8.5, color="0.2")
    if s.get("listing"):
        lst = s["listing"]
        axes[0].plot([s["k_book"]], [lst["dt"]], marker="*", ms=16, color="gold", mec="black", ls="none",
                     label=f"the book's Matlab listing: explicit Euler, dt = {lst['dt']:g} s, k = {s['k_book']:g} N/m")
    handles = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, handle)
    fig.legend(handles.values(), handles.keys(), loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.suptitle(f"1.8.3 spring pendulum, from the book's initial conditions over {s['horizon']:g} s\n"
                 "markers: bisection (filled: the book's equations; open: MuJoCo, drawn shifted right); "
                 "wide lines: linear theory about the relative equilibrium on the disk", fontsize=10)
    fig.tight_layout(rect=(0, 0.16, 1, 1))
    fig.savefig(path, dpi=120)
    plt.close(fig)


def figure_lyapunov(result, path):
    plt = _plt()
    s = result["series"]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.6))
    colors = ["tab:blue", "tab:red", "tab:green", "tab:purple"]
    for (label, (t, logs)), color in zip(s["curves"].items(), colors):
        a1.plot(t, logs, color=color, label=label)
        a2.plot(t[1:], logs[1:] / t[1:], color=color, label=label)
    rows = s["rows"]
    for (_, r), color in zip(rows.iterrows(), colors):
        if r.get("status") == "chaotic":
            a2.axhline(r["lambda"], color=color, ls=":", lw=1)
    a1.set_xlabel("t [s]")
    a1.set_ylabel("ln(|d(t)| / |d(0)|), accumulated")
    a1.set_title("stretch of a small separation (Benettin)", fontsize=10)
    a2.set_xlabel("t [s]")
    a2.set_ylabel("finite-time Lyapunov exponent lambda(t) [1/s]")
    a2.set_xscale("log")
    a2.set_title("convergence: flat = chaotic, falling like ln(t)/t = regular", fontsize=10)
    for a in (a1, a2):
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=8)
    fig.suptitle("1.9 double pendulum: sensitivity to initial conditions", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def figure_energy_drift(result, path):
    plt = _plt()
    s = result["series"]
    fig, ax = plt.subplots(figsize=(9, 5.4))
    widths = {"mujoco:Euler": 3.5, "mujoco:implicitfast": 1.2, "mujoco:RK4": 3.5}
    dashes = {"mujoco:Euler": "-", "mujoco:implicitfast": ":", "mujoco:RK4": "-"}
    alphas = {"mujoco:Euler": 0.35, "mujoco:RK4": 0.35}
    floor = 1e-16
    for label, (t, drift) in s["curves"].items():
        key = label.split(" (")[0]
        st = _style(label)
        ax.plot(t[1:], np.maximum(drift[1:], floor), color=st.get("color"), lw=widths.get(key, 1.2),
                ls=dashes.get(key, "-"), alpha=alphas.get(key, 1.0), label=label)
    for _, r in s["rows"].iterrows():
        if r.get("status") == "unstable" and r.get("t_fail") is not None:
            ax.axvline(r["t_fail"], color=_style(r["method"]).get("color", "k"), ls="--")
            ax.text(r["t_fail"], 1, f"{r['method']} blows up", rotation=90, fontsize=8, va="top")
    ax.set_yscale("log")
    ax.set_xscale("log")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("|E(t) - E(0)| / (E(0) - E_rest)")
    ax.set_title(f"1.9 double pendulum: energy error of each method at dt = {s['dt']:g} s "
                 f"(the book's listing's step), E(0) - E_rest = {s['swing']:.3g} J\n"
                 "MuJoCo's Euler and implicitfast lie on semi-implicit Euler, MuJoCo's RK4 on RK4 "
                 "(wide pale lines under the thin ones)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="lower right", ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def figure_euler_singularity(result, path):
    plt = _plt()
    s = result["series"]
    rows = s["rows"]
    passes = [p for p in s["passes"] if p.get("status") == "ok"]
    fig, axes = plt.subplots(1, 2 if passes else 1, figsize=(12, 4.8) if passes else (6.5, 4.8))
    axes = np.atleast_1d(axes)
    ax = axes[0]
    styles = {"reference (Euler angles)": dict(color="tab:red", marker="o", lw=1.5),
              "truth at the rounded Euler rates": dict(color="tab:orange", marker="v", lw=1, ls="--"),
              "mujoco (quaternion)": dict(color="tab:green", marker="s", lw=1, mfc="none"),
              "pinocchio (quaternion)": dict(color="tab:blue", marker="x", lw=1)}
    floor = 1e-18
    for source, group in rows.groupby("source", sort=False):
        err = group["error"].astype(float).fillna(np.inf)
        ax.plot(group["nutation"], np.clip(err, floor, 1e3), label=source, **styles.get(source, {}))
    ax.axhline(EPS, color="0.5", ls=":", lw=1)
    ax.text(rows["nutation"].max(), EPS / 1.5, "machine epsilon", ha="left", va="top", fontsize=8, color="0.4")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.invert_xaxis()
    ax.set_xlabel("nutation [rad] (toward upright ->)")
    ax.set_ylabel("relative error of the angular acceleration")
    ax.set_title("same physical state, body angular acceleration\n(errors below 1e-18 drawn at 1e-18)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    if passes:
        ax = axes[1]
        colors = ["tab:red", "tab:purple", "tab:brown", "tab:pink"]
        for p, color in zip(passes, colors):
            for key, ls, label in (("dop853", "-", "DOP853"), ("rk4", "--", "fixed RK4")):
                x = p.get(key, {})
                if x.get("status") == "ok":
                    ax.plot(p["t"], np.clip(x["error"], floor, 10), color=color, ls=ls, lw=1.1,
                            label=f"Euler angles, {label}, closest {p['closest']:.0e} rad")
                elif x.get("fail", {}).get("t") is not None:
                    ax.plot([x["fail"]["t"]], [1.0], marker="X", ms=11, color=color, ls="none",
                            label=f"Euler angles, {label}, closest {p['closest']:.0e} rad: blows up "
                                  f"at t = {x['fail']['t']:.3g} s")
        ax.plot(passes[0]["t"], np.maximum(passes[0]["error_mj"], floor), color="tab:green", lw=1.5,
                label="MuJoCo RK4 (quaternion) vs its half-step twin")
        ax2 = ax.twinx()
        closest = min(passes, key=lambda p: p["closest"])
        ax2.plot(closest["t"], closest["nutation"], color="0.55", lw=0.8)
        ax2.set_yscale("log")
        ax2.set_ylabel("nutation [rad] of the closest passage (grey)", color="0.4")
        ax.set_yscale("log")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("axis direction error against MuJoCo [rad]")
        ax.set_title("a top whose axis swings past the vertical, 3 aims", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.set_ylim(floor / 10, 1e9)
        ax.legend(fontsize=7, loc="upper right", framealpha=0.92)
    fig.suptitle("1.10 spinning top: the Euler-angle equations near zero nutation", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def figure_sleeping_top(result, path):
    plt = _plt()
    s = result["series"]
    trail = s["trail"]
    fig, ax = plt.subplots(figsize=(8.5, 5.2))
    spins = np.linspace(0.985 * s["criterion"], 1.01 * s["criterion"], 160)
    reached = np.array([top_nutation(s["params"], x, s["n0"], s["horizon"])[0] for x in spins])
    ax.plot(spins, reached, color="0.35", lw=1.8,
            label=f"first integrals (exact): largest nutation within {s['horizon']:g} s")
    ran = trail[trail["status"] == "ran"]
    for stable, marker, color, label in ((True, "o", "tab:green", "MuJoCo: stays below the bound"),
                                         (False, "x", "tab:red", "MuJoCo: falls past the bound")):
        g = ran[ran["stable"] == stable]
        ax.plot(g["spin"], g["max_nutation"], ls="none", marker=marker, color=color, ms=8, mew=2, label=label)
    ax.axvline(s["criterion"], color="black", ls="--",
               label=f"criterion s_c = 2 sqrt(Ixx m g h) / Izz = {s['criterion']:.4g} rad/s")
    ax.axvline(s["finite"], color="tab:blue", ls=":", label=f"threshold for this bound and horizon: {s['finite']:.5g}")
    ax.axhline(s["bound"], color="tab:orange", ls=":", label=f"bound {s['bound']:g} rad")
    ax.set_yscale("log")
    ax.set_xlim(spins[0], spins[-1])
    ax.set_xlabel("spin s [rad/s]")
    ax.set_ylabel("largest nutation over the run [rad]")
    ax.set_title(f"1.10 sleeping top: started {s['n0']:g} rad from upright with only the spin, Mz = 0, "
                 f"{s['horizon']:g} s\nMuJoCo {s['method']} at dt = {s['dt']:g} s (points outside the window not shown)",
                 fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
