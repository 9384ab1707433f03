"""1.8.3 spring pendulum: the largest stable step of each method against the spring stiffness."""

import math
import time

import numpy as np
import pandas as pd
from scipy.optimize import fsolve

from dyncheck.case.folder import settings_of
from dyncheck.common.style import legend_below, method_style, panels, save, title
from dyncheck.run.simulate import attempt, describe, fastest_frequency, simulate
from dyncheck.studies.stability.common import (FAMILY, SHARP, Guarded, Map, Study, fmt, grid_step, limit_step, rms,
                                               run_fixed, study_result)


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
    return np.array([rms(acc[last, i]) / rms(acc[first, i]) for i in range(acc.shape[1])])


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


def stable_steps_at(case, settings, k, methods, trail):
    """`stable_step`'s rows at stiffness k at the case's spin: the exact solution's (bounded or a physical
    runaway), then each method's largest stable and smallest blow-up step; each trial run is added to `trail`."""
    p = case.params
    m, omega_base = p["m"], p["alpha_rate"] + p["beta_rate"]
    T, G, resolution = settings["horizon"], settings["growth"], settings["resolution"]
    escape = settings["escape"]
    source = settings.get("source", "reference")
    span = 0.75 * T  # the growth is measured from the first quarter of the horizon to the last
    runaway_T = case.initial[2]
    rows = []
    variant = case.with_params(k=k)
    lin = spring_linearisation(case, k)
    # The exact solution from the book's initial conditions: bounded, or a physical runaway?
    exact_model = Guarded(variant.model(source), 1, escape, "DOP853", 1)
    exact_long, fail = attempt(lambda: simulate(exact_model, variant.initial[:2], runaway_T, "DOP853",
                                                rtol=settings["rtol"], output_step=1e-3, work=False,
                                                omega=fastest_frequency(variant)))
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
        return rows
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
    return rows


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
    settings = in_newtons_per_metre(settings)
    p = case.params
    m, omega_base = p["m"], p["alpha_rate"] + p["beta_rate"]
    k_crit = m * omega_base**2
    T, G = settings["horizon"], settings["growth"]
    escape = settings["escape"]
    methods, source = settings["methods"], settings.get("source", "reference")
    span = 0.75 * T  # the growth is measured from the first quarter of the horizon to the last
    runaway_T = case.initial[2]
    rows, trail = [], []

    for k in settings["k"]:
        if progress:
            progress(f"stable step, k = {k:g} N/m")
        rows += stable_steps_at(case, settings, k, methods, trail)

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
                value = f"physical runaway: |l| > {escape:g} m at t = {fmt(r['t_fail'])} s"
            elif r.get("t_fail") is not None:
                value = f"runs away with it at t = {fmt(r['t_fail'])} s (exact: {fmt(r.get('t_exact'))} s)"
            else:
                value = f"stays within the bound (the exact solution escapes at {fmt(r.get('t_exact'))} s)"
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
                           "theory [s]": fmt(r.get("h_theory")),
                           "smallest blow-up step": blow,
                           "linear limit [s]": fmt(r.get("h_limit"))})
    table = pd.DataFrame(table_rows)

    findings = _stable_step_findings(case, settings, data, crit, listing, k_crit, span)
    series = {"rows": data, "curves": curves, "k_crit": k_crit, "crit": crit, "listing": listing,
              "trail": pd.DataFrame(trail), "horizon": T, "growth": G, "k_book": case.params["k"]}
    data = data.assign(horizon=T, growth_limit=G)
    return study_result(case, "stable_step", "Largest stable step against the spring stiffness", settings,
                   data, table, findings, series, start)


def in_newtons_per_metre(settings):
    """The settings with the stiffnesses k, k_stiff and k_fit in N/m: the table gives them in multiples of its
    `k_scale` (1 without it), an expression of the parameters, so that they follow k_crit = m Omega^2 under --set;
    each rounded to 3 significant digits (a sample point 0.5 % off its multiple, and 3000 N/m in the tables, not
    2997.89)."""
    scale = settings.get("k_scale", 1.0)
    newtons = lambda k: float(f"{scale * k:.3g}")
    return {**settings, "k": [newtons(k) for k in settings["k"]],
            **{key: newtons(settings[key]) for key in ("k_stiff", "k_fit") if key in settings}}


def _critical_stiffness(case, settings, source, escape, horizon):
    """Bisection on k for the exact solution from the book's initial conditions: runaway below, bounded above."""
    k_crit = case.params["m"] * (case.params["alpha_rate"] + case.params["beta_rate"]) ** 2

    def runs_away(k):
        variant = case.with_params(k=k)
        model = Guarded(variant.model(source), 1, escape, "DOP853", 1)
        _, fail = attempt(lambda: simulate(model, variant.initial[:2], horizon, "DOP853", rtol=settings["rtol"],
                                           output_step=horizon / 100, work=False, omega=fastest_frequency(variant)))
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
                                           rtol=settings["rtol"], output_step=dt * 4, work=False,
                                           omega=fastest_frequency(case)))
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
            "acc_ratio": rms(acc(out)[last, 1]) / rms(acc(exact)[last, 1])}


FIGURE_RESOLUTION = 0.01  # of a curve's span: what a printed figure shows (the findings' "1 % a figure resolves")


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
                   f"(k = {r0['k']:g}: stable to {r0['h_stable']:.3g} s, blow-up at {fmt(r0['h_blowup'])} s): the "
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
                   "the exact RMS: the listing's figure of l(t) is "
                   + (f"off the exact motion by more than the {FIGURE_RESOLUTION:.0%} of its span that a figure "
                      "resolves." if listing["l_error"] > FIGURE_RESOLUTION * listing["l_range"] else
                      f"within the {FIGURE_RESOLUTION:.0%} of its span that a figure resolves."))
    return out


def figure_stable_step(result, path, name):
    """The largest stable and the smallest blow-up step against the stiffness; returns the caption."""
    s = result.series
    rows, curves = s["rows"], s["curves"]
    measured = rows[rows["status"] == "measured"]
    kmin = min(rows["k"].min(), s["k_crit"]) / 1.5
    fig, axes = panels(2, 1, 8.9, sharex=True, sharey=True)
    axes = axes[:, 0]
    families = [("explicit Euler", "explicit Euler"), ("semi-implicit Euler", "semi-implicit Euler = MuJoCo Euler, implicitfast"),
                ("RK4", "RK4 = MuJoCo RK4")]
    offsets = {"mujoco:Euler": 1.06, "mujoco:implicitfast": 1.12, "mujoco:RK4": 1.06}
    shown = [(axes[0], "h_stable", "", f"largest stable step: the oscillation grows at most {s['growth']:g} x "
                                        f"over {0.75 * s['horizon']:g} s"),
             (axes[1], "h_blowup", " limit", "smallest blow-up step: |l| > escape bound, NaN or MuJoCo reset")]
    for ax, column, suffix, heading in shown:
        for method, label in families:
            key = method + suffix
            if key in curves:
                theory = ("theory: growth %g x over %g s" % (s["growth"], 0.75 * s["horizon"]) if not suffix
                          else "theory: " + {"semi-implicit Euler": "2/omega", "RK4": "2 sqrt(2)/omega"}[method])
                ax.plot(curves["k"], curves[key], color=method_style(method)["color"], lw=6, alpha=0.25,
                        label=f"{theory}, {label}", solid_capstyle="butt")
        for method, group in measured.groupby("method", sort=False):
            group = group.dropna(subset=[column])
            if group.empty:
                continue
            st = method_style(method)
            filled = not method.startswith("mujoco")
            ax.plot(group["k"] * offsets.get(method, 1.0), group[column], ls="-" if filled else "none", lw=0.8,
                    ms=5 if filled else 7, marker=st["marker"], color=st["color"],
                    mfc=st["color"] if filled else "none", mew=1.6, label=f"measured, {method}")
        ax.axvspan(kmin, s["k_crit"], color="0.88", zorder=0)
        ax.axvline(s["k_crit"], color="0.3", ls="--", lw=1)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(kmin, rows["k"].max() * 1.6)
        ax.set_title(heading)
        ax.set_ylabel("time step dt [s]")
        ax.grid(True, which="both")
    finite = [np.nanmin(curves[m]) for m, _ in families if m in curves]
    top = [np.nanmax(curves[m + " limit"]) for m, _ in families if m + " limit" in curves]
    ymin, ymax = min(finite) / 3, max(top) * 4
    axes[0].set_ylim(ymin, ymax)
    axes[1].set_xlabel("spring stiffness k [N/m]")
    for ax in axes:
        ax.text(kmin * 1.1, math.sqrt(ymin * ymax), f"physical\nrunaway:\nk < k_crit\n= {s['k_crit']:.4g} N/m",
                ha="left", va="center", fontsize=8, color="0.2")
    if s.get("listing"):
        lst = s["listing"]
        axes[0].plot([s["k_book"]], [lst["dt"]], marker="*", ms=12, color="gold", mec="black", ls="none",
                     label=f"the book's Matlab listing: explicit Euler, dt = {lst['dt']:g} s, k = {s['k_book']:g} N/m")
    legend_below(fig, ncol=1)
    fig.suptitle(title(name, f"the largest stable step against the stiffness, over {s['horizon']:g} s"))
    save(fig, path)
    listing = s.get("listing")
    return ("The largest time step at which each method stays stable (top) and the smallest at which it blows up"
            " (bottom), against the spring's stiffness k, from the book's initial conditions. Markers: measured by"
            " bisection (filled: the book's equations; open: MuJoCo, drawn shifted right); wide pale lines: the"
            " linear theory about the relative equilibrium on the disk. Below"
            f" k_crit = m Omega^2 = {s['k_crit']:.4g} N/m (shaded) the spring cannot hold the particle: the exact"
            " motion runs away too and no step helps. Stiffer springs need steps falling like 1/k (explicit Euler)"
            " or 1/sqrt(k) (the others)."
            + (f" The star: the book's Matlab listing, explicit Euler at dt = {listing['dt']:g} s and"
               f" k = {s['k_book']:g} N/m." if listing else ""))


STUDIES = {"stable_step": Study(stable_step, figure_stable_step, (
    "k", "methods", "horizon", "growth", "resolution", "escape", "max_steps", "rtol", "k_resolution", "output_rows"))}


# -- the campaign's map: the largest stable step over stiffness and spin --------------------------------------------

MAP_METHOD = "RK4"  # one method per map: the classical scheme, with a closed-form limit
MAP_K = (50.0, 2e4)  # N/m, logarithmically: through k_crit = m Omega^2 at every spin of the grid
MAP_SPIN = (10.0, 40.0)  # rad/s, Omega = alpha' + beta' (the arm's rate kept, the disk's changed)


def map_grid(case, n):
    return ("spring stiffness k [N/m]", np.geomspace(*MAP_K, n),
            "spin Omega = alpha' + beta' [rad/s]", np.linspace(*MAP_SPIN, n))


def map_cell(case, k, spin):
    """RK4's largest stable step at stiffness k and spin Omega (`stable_steps_at`, the study's settings), against the
    linear theory's; a physical runaway (the exact solution leaves the bound) has none."""
    variant = case.with_params(beta_rate=spin - case.params["alpha_rate"])
    rows = stable_steps_at(variant, settings_of(case, "stable_step"), k, [MAP_METHOD], [])
    measured = next(r for r in rows if r["method"] == MAP_METHOD)
    value = measured.get("h_stable") if measured["status"] == "measured" else None
    theory = measured.get("h_theory")
    return {"value": math.nan if value is None else value, "theory": math.nan if theory is None else theory,
            "status": measured["status"]}


def map_runaway(case, ks):
    """The spin at which the spring lets go, k = m Omega^2."""
    return np.sqrt(np.asarray(ks) / case.params["m"])


MAPS = {"stable_step": Map(f"{MAP_METHOD}'s largest stable step over stiffness and spin", map_grid, map_cell,
                           "largest stable step [s]", "linear theory about the relative equilibrium",
                           boundary=map_runaway, log=(True, False))}
