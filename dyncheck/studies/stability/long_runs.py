"""Studies of long runs, for any case: the finite-time Lyapunov exponent and the agreement horizon of
two sources, and each method's long-run energy drift."""

import math
import time

import numpy as np
import pandas as pd

from dyncheck.checks.horizon import agreement_horizon, benettin
from dyncheck.common.style import legend_below, method_style, panels, save, thin, title
from dyncheck.run.simulate import MUJOCO_METHODS, SCIPY_METHODS, attempt, describe, fastest_frequency, simulate
from dyncheck.studies.stability.common import EPS, fmt, study_result

# A separation below this fraction of the state's size (its rates scaled) grows by the linearised equations to
# within about as much of itself: the nonlinear terms are of the order of the separation squared.
LINEAR_SEPARATION = 1e-4


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
                     "horizon_integrators": math.log(tol / eps0) / lam if chaotic else None,
                     "interval_growth": float(math.exp(np.max(np.diff(logs))))})
    data = pd.DataFrame(rows)
    check_h, details = agreement_horizon(case)
    table = pd.DataFrame([{
        "initial conditions": r["initial"],
        "motion": r["status"],
        f"lambda at {settings['horizon']:g} s [1/s]": fmt(r.get("lambda")),
        f"lambda at {settings['horizon'] / 2:g} s [1/s]": fmt(r.get("lambda_half")),
        f"agreement horizon, {eps0:g} -> {tol:g} [s]": (fmt(r.get("horizon_integrators"), ".3g")
                                                       if r.get("horizon_integrators") else
                                                       f"> {settings['horizon']:g} (no exponential growth)"),
        "lambda over the second half [1/s]": (f"{r['lambda_min']:.3g}-{r['lambda_max']:.3g}"
                                               if r.get("lambda_min") is not None else "-"),
        f"agreement horizon, rounding {EPS:.1e} -> {tol:g} [s]": (fmt(r.get("horizon_rounding"), ".3g")
                                                                 if r.get("horizon_rounding")
                                                                 else f"> {settings['horizon']:g}"),
    } for r in rows])
    findings = [f"Largest Lyapunov exponent by two neighbouring trajectories (Benettin; DOP853 at rtol "
                f"{settings['rtol']:g}, distance {settings['d0']:g} in the state with rates divided by "
                f"rate_scale = {settings['rate_scale']:.4g} rad/s, "
                f"renormalised every {settings['renormalise']:g} s) over {settings['horizon']:g} s. The agreement "
                f"horizon T = ln(tol/eps0)/lambda is how long two sources that differ by eps0 stay within tol."]
    ran = [r for r in rows if r["status"] != "unstable"]
    if ran:
        growth = max(r["interval_growth"] for r in ran)
        reached = settings["d0"] * growth
        findings.append(f"Between renormalisations the separation grows at most {growth:.3g} times, from "
                        f"{settings['d0']:g} to {reached:.2g}: "
                        + ("far below the state's own size, in the linear regime that the exponent assumes." if
                           reached <= LINEAR_SEPARATION else
                           f"beyond {LINEAR_SEPARATION:g} of the state's size, where the nonlinear terms bend the "
                           "separation: the exponent is underestimated; renormalise more often."))
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
    return study_result(case, "lyapunov", "Lyapunov exponent and the agreement horizon", settings, data, table,
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
                                             work=False, omega=fastest_frequency(case), **kwargs))
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
        "step": fmt(r.get("dt")),
        "max |dE|/E_swing, 1 s": fmt(r.get("drift_1s")),
        f"{T / 10:g} s": fmt(r.get("drift_T10")),
        f"{T:g} s": fmt(r.get("drift_T")),
        "growth exponent": fmt(r.get("growth_exponent"), ".2f"),
        "character": r.get("character") if r["status"] == "ran" else describe({"status": "unstable", **r,
                                                                               "t": r.get("t_fail"),
                                                                               "step": r.get("step_fail")}),
    } for r in rows])
    dop = f", DOP853 at rtol {settings['rtol']:g}" if "DOP853" in settings["methods"] else ""
    findings = [f"From the book's initial conditions over {T:g} s at dt = {dt:g} s{dop}; "
                f"the error is |E(t) - E(0)| relative to the swing's energy above rest, {swing_words(swing)}. "
                "The growth exponent is d ln(max |dE|) / d ln t from T/10 to T: 0 for a bounded error, 1 for a "
                "linear drift."]
    ran = data[data["status"] == "ran"] if "status" in data else data
    # Optional: a state whose energy above rest the motion must exceed to run away (over the top, say).
    whirl = settings.get("whirl_q")
    top = (reference.energy(0.0, np.array(whirl), np.zeros(len(v0))) - rest) / swing if whirl else None
    for _, r in ran.iterrows():
        text = (f"{r['method']}: {r['character']} (growth exponent {r['growth_exponent']:.2f}); "
                f"{r['drift_1s']:.2g} after 1 s, {r['drift_T10']:.2g} after {T / 10:g} s, {r['drift_T']:.2g} by {T:g} s")
        if r["drift_T"] > 1.0 and top:
            state = f"the state q = ({', '.join(f'{x:.4g}' for x in whirl)})"
            text += (f": more than the {top:.3g} swing energies that {state} holds above rest, so it can go over "
                     "the top" if r["drift_T"] > top else
                     f": less than the {top:.3g} swing energies that {state} holds above rest, so it cannot yet "
                     "go over the top")
        findings.append(text + ".")
    for _, r in (data[data["status"] == "unstable"].iterrows() if "status" in data else []):
        findings.append(f"{r['method']}: unstable at t = {fmt(r['t_fail'])} s (step {r['step_fail']}): {r['why']}.")
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
    return study_result(case, "energy_drift", "Long-run energy error of each method", settings, data, table,
                   findings, series, start)


def swing_words(swing):
    """The energy the drift is relative to, as the findings and the caption both write it."""
    return f"E(0) - E_rest = {swing:.3g} J"


LINES = ("-", "--", ":", "-.")  # one per curve of a study, with a marker: told apart in grey
MARKERS = ("o", "s", "^", "D")


def figure_lyapunov(result, path, name):
    """The stretch of a small separation and the finite-time exponent, one curve per start; returns the caption."""
    s = result.series
    fig, axes = panels(2, 1, 5.6)
    a1, a2 = axes[:, 0]
    colors = ["tab:blue", "tab:red", "tab:green", "tab:purple"]
    for k, (label, (t, logs)) in enumerate(s["curves"].items()):
        style = dict(color=colors[k % 4], ls=LINES[k % 4], marker=MARKERS[k % 4], mfc="none", markevery=(0.02 * k, 0.1))
        t, logs = thin(np.asarray(t)), thin(np.asarray(logs))
        a1.plot(t, logs, label=label, **style)
        a2.plot(t[1:], logs[1:] / t[1:], **style)
    rows = s["rows"]
    for k, (_, r) in enumerate(rows.iterrows()):
        if r.get("status") == "chaotic":
            a2.axhline(r["lambda"], color=colors[k % 4], ls=":", lw=1,
                       label="dotted: the exponent measured for a chaotic start (its colour)")
    a1.set_ylabel("ln(|d(t)| / |d(0)|) [1]")
    a1.set_title("stretch of a small separation (Benettin), accumulated")
    a2.set_xlabel("t [s]")
    a2.set_ylabel("lambda(t) [1/s]")
    a2.set_xscale("log")
    a2.set_title("finite-time Lyapunov exponent: flat = chaotic, falling like ln(t)/t = regular")
    for a in (a1, a2):
        a.grid(True, which="both")
    fig.suptitle(title(name, "sensitivity to initial conditions"))
    legend_below(fig, ncol=2)
    save(fig, path)
    verdicts = "; ".join(f"{r['initial']}: {r['status']}" + (f", lambda = {r['lambda']:.3g} 1/s" if r.get("status") == "chaotic"
                                                             else "") for _, r in rows.iterrows())
    return ("Top: how far two neighbouring trajectories move apart from each start (ln of the separation's growth,"
            " renormalised and accumulated); bottom: that growth over t, the finite-time exponent lambda(t), the"
            " dotted lines the exponents measured for chaotic starts. A flat lambda(t) means chaos: errors grow"
            f" e-fold every 1/lambda seconds; one falling like ln(t)/t a regular motion. Here: {verdicts}.")


def figure_energy_drift(result, path, name):
    """The energy error of each method over the long run; returns the caption."""
    s = result.series
    fig, axes = panels(1, 1, 4.8)
    ax = axes[0, 0]
    widths = {"mujoco:Euler": 3.5, "mujoco:implicitfast": 1.2, "mujoco:RK4": 3.5}
    dashes = {"mujoco:Euler": "-", "mujoco:implicitfast": ":", "mujoco:RK4": "-"}
    alphas = {"mujoco:Euler": 0.35, "mujoco:RK4": 0.35}
    floor = 1e-16
    for k, (label, (t, drift)) in enumerate(s["curves"].items()):
        key = label.split(" (")[0]
        st = method_style(label)
        t, drift = thin(np.asarray(t)[1:]), thin(np.asarray(drift)[1:])
        ax.plot(t, np.maximum(drift, floor), color=st.get("color"), marker=st.get("marker"), mfc="none",
                markevery=(0.015 * k, 0.12), lw=widths.get(key, 1.2), ls=dashes.get(key, "-"),
                alpha=alphas.get(key, 1.0), label=label)
    for _, r in s["rows"].iterrows():
        if r.get("status") == "unstable" and r.get("t_fail") is not None:
            ax.axvline(r["t_fail"], color=method_style(r["method"]).get("color", "k"), ls="--")
            ax.text(r["t_fail"], 1, f"{r['method']} blows up", rotation=90, fontsize=8, va="top")
    ax.set_yscale("log")
    ax.set_xscale("log")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("|E(t) - E(0)| / (E(0) - E_rest) [1]")
    ax.grid(True, which="both")
    fig.suptitle(title(name, f"energy error of each method at dt = {s['dt']:g} s"))
    legend_below(fig, ncol=3)
    save(fig, path)
    ends = "; ".join(f"{r['method']} {r['character']}" + (f" ({r['drift_T']:.2g} at the end)" if pd.notna(r.get("drift_T"))
                                                          else "") for _, r in s["rows"].iterrows())
    return (f"Each method's energy error over {s['horizon']:g} s from the book's initial conditions at dt = {s['dt']:g} s,"
            f" relative to the swing's energy above rest ({swing_words(s['swing'])}), on log axes (colour"
            " and marker per method). MuJoCo's Euler and implicitfast lie on semi-implicit Euler, MuJoCo's RK4 on RK4"
            f" (wide pale lines under the thin ones). {ends}.")
