"""Forced cart-pendulum: the steady-state amplitudes against the linear theory."""

import math
import time
from dataclasses import dataclass

import numpy as np
import pandas as pd

from dyncheck.common.style import SOURCE_STYLE, SWEEP_STYLE, legend_below, panels, save, title
from dyncheck.run.simulate import attempt, describe, fastest_frequency, simulate
from dyncheck.studies.stability.common import Study, fmt, study_result

PUSHED = "x"  # the coordinate that case.toml's [scene.applied] pushes with F0 cos(Omega t)
SWINGING = "theta"  # the coordinate whose amplitude the neglected (cubic) terms grow with
PARABOLA = 3 / 128
"""The vertex of the parabola through three samples of A cos(Omega t), d apart, misses A by at most
(Omega d)^4 x 3/128 of A, wherever the true peak lies between the samples (the worst is at the midpoint)."""
DISPLAY = {"m": (1e3, "mm"), "rad": (1e3, "mrad")}  # amplitudes on the page and in the figure
FINE = {"m": "µm", "rad": "µrad"}  # a thousandth of DISPLAY's: the departures from the linear theory


@dataclass(frozen=True)
class LinearTheory:
    """The derivation linearised at rest: M0 q'' + C q' + K q = F cos(Omega t)."""
    M0: np.ndarray
    K: np.ndarray
    C: np.ndarray
    F: np.ndarray  # the push's amplitude on each coordinate
    step: float  # of the central differences
    difference_error: float  # their error relative to the largest entry of K and C (Richardson)

    def stiffness(self, omega):
        """The dynamic stiffness Z(omega) = K - omega^2 M0 + i omega C."""
        return self.K - omega**2 * self.M0 + 1j * omega * self.C

    def amplitudes(self, omega):
        """The steady state's complex amplitudes X, q(t) = Re(X e^(i omega t))."""
        return np.linalg.solve(self.stiffness(omega), self.F)

    def modes(self):
        """Eigenvalues and eigenvectors of the free motion in the state z = (q, q')."""
        n = len(self.F)
        inverse = np.linalg.inv(self.M0)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-inverse @ self.K, -inverse @ self.C]])
        return np.linalg.eig(A)

    def undamped_frequencies(self):
        """The natural frequencies without the dampers, sqrt of the eigenvalues of M0^-1 K, ascending."""
        return np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(self.M0, self.K)).real))


def linearisation(case, step):
    """The derivation (case.model("reference"): its mass_matrix and forces) linearised at rest, q = v = 0:
    M0 its mass matrix there, K = -df/dq and C = -df/dv by central differences of its forces f(t, q, v) at
    t = 0.  The push is on there but depends on t alone, so it cancels in every difference; its
    amplitude F0 is read from the parameters.  The differences' error is ~ step^2 f''' / 6 (f is
    trigonometric in theta, f''' ~ f': ~ step^2 / 6 relative) plus rounding, eps |f| / step; both are
    measured by the change with the step doubled, over 3 (Richardson: the step^2 term quadruples)."""
    model = case.model("reference")
    n = len(case.coords)
    rest = np.zeros(n)

    def jacobians(h):
        f = lambda q, v: model.forces(0.0, q, v)
        K = -np.column_stack([(f(rest + h * e, rest) - f(rest - h * e, rest)) / (2 * h) for e in np.eye(n)])
        C = -np.column_stack([(f(rest, rest + h * e) - f(rest, rest - h * e)) / (2 * h) for e in np.eye(n)])
        return K, C

    K, C = jacobians(step)
    K2, C2 = jacobians(2 * step)
    scale = max(np.abs(K).max(), np.abs(C).max())
    error = max(np.abs(K2 - K).max(), np.abs(C2 - C).max()) / 3 / scale
    F = np.zeros(n)
    F[case.coords.index(PUSHED)] = case.params["F0"]
    return LinearTheory(np.asarray(model.mass_matrix(0.0, rest, rest), dtype=float), K, C, F, step, error)


def nonlinear_bound(case, theory, omega):
    """Each coordinate's amplitude deviation from the linear theory, relative to it, to first order in
    the neglected terms: a bound.

    Along the linear motion the terms the linearisation drops are, at their peaks (amplitudes |X_x|,
    |X_theta| = a, each term a product of three sinusoids of frequency omega):
      x row:     m l (cos theta - 1) theta''  <= m l a^2 / 2 omega^2 |X_theta|
                 -m l sin(theta) theta'^2     <= m l a^2 omega^2 |X_theta|
      theta row: m l (cos theta - 1) x''      <= m l a^2 / 2 omega^2 |X_x|
                 m g l (sin theta - theta)    <= m g l a^2 / 6 |X_theta|
    (dZ |X|).  A product of three unit sinusoids has a first harmonic of at most 3/4 and a third of at
    most 1/4; the linear system answers them through Z(omega)^-1 and Z(3 omega)^-1, and (max - min) / 2
    moves by at most the sum: |dq_i| <= [(3/4 |Z(omega)^-1| + 1/4 |Z(3 omega)^-1|) dZ |X|]_i (entrywise
    absolute values: every phase at its worst).  The next order is a^2 smaller."""
    p = case.params
    m, l, g = p["m"], p["l"], p["g"]
    X = np.abs(theory.amplitudes(omega))
    i, j = case.coords.index(PUSHED), case.coords.index(SWINGING)
    a2 = X[j] ** 2
    dZ = np.zeros((len(X), len(X)))
    dZ[i, j] = m * l * a2 * omega**2 * (1 / 2 + 1)
    dZ[j, i] = m * l * a2 * omega**2 / 2
    dZ[j, j] = m * g * l * a2 / 6
    response = (0.75 * np.abs(np.linalg.inv(theory.stiffness(omega)))
                + 0.25 * np.abs(np.linalg.inv(theory.stiffness(3 * omega))))
    return response @ dZ @ X / X


def transient_left(theory, omega, t0):
    """Of a start from rest at q = 0: the free motion that cancels the steady one's state at t = 0,
    z0 = -(Re X, Re(i omega X)), split into the linear modes (z0 = V c); each coordinate's envelope at t0,
    sum_k |V_ik c_k| e^(Re lambda_k t0), relative to |X_i|."""
    X = theory.amplitudes(omega)
    eigenvalues, V = theory.modes()
    c = np.linalg.solve(V, -np.concatenate([X.real, (1j * omega * X).real]))
    n = len(X)
    return np.abs(V[:n] * c) @ np.exp(eigenvalues.real * t0) / np.abs(X)


def amplitude(t, y, start):
    """(max - min) / 2 of y over start <= t < t[-1], each extreme refined to the vertex of the parabola
    through it and its two neighbours."""
    inside = np.nonzero(t >= start)[0][:-1]  # the last sample has no right neighbour

    def vertex(i):
        a, b, c = y[i - 1], y[i], y[i + 1]
        return b - (a - c) ** 2 / (8 * (a - 2 * b + c))

    return (vertex(inside[np.argmax(y[inside])]) - vertex(inside[np.argmin(y[inside])])) / 2


def plan(theory, omega, settings):
    """The run: from rest to t_end, measured over the last `periods` forcing periods, output every d.

    The transient decays at least like e^(-sigma t), sigma the slowest decay rate of the linear modes:
    the window starts after ln(1 / settle) / sigma, rounded up to whole periods.  d: the largest
    multiple of MuJoCo's step whose peak sampling error (Omega d)^4 x 3/128 (PARABOLA) is within
    `sampling`; t_end a whole number of outputs (each source's samples at the grid's times)."""
    sigma = -np.max(theory.modes()[0].real)
    period = 2 * math.pi / omega
    settle = math.ceil(math.log(1 / settings["settle"]) / sigma / period)
    h = settings["mujoco_step"]
    every = max(1, math.floor((settings["sampling"] / PARABOLA) ** 0.25 / (omega * h)))
    d = every * h
    t_end = math.ceil((settle + settings["periods"]) * period / d) * d
    return {"output_step": d, "t_end": t_end, "start": t_end - settings["periods"] * period,
            "sampling": PARABOLA * (omega * d) ** 4}


def runs(case, sources, run_plan, settings):
    """Each source's run from rest: {source: (frame, None) or (None, failure)}.  The derivation and
    Pinocchio by DOP853 at `rtol`, MuJoCo by its own RK4 at `mujoco_step`."""
    rest = (np.zeros(len(case.coords)), np.zeros(len(case.coords)))
    how = {"reference": dict(method="DOP853", rtol=settings["rtol"], omega=fastest_frequency(case)),
           "pinocchio": dict(method="DOP853", rtol=settings["rtol"], omega=fastest_frequency(case)),
           "mujoco": dict(method="mujoco:RK4", dt=settings["mujoco_step"])}
    return {source: attempt(lambda: simulate(case.model(source), rest, run_plan["t_end"], **how[source],
                                             output_step=run_plan["output_step"], work=False))
            for source in sources}


def steady_state(case, settings, progress=None):
    """The steady-state amplitude of each coordinate under the push F0 cos(Omega t): the linear theory
    (`linearisation`) against the derivation, MuJoCo and Pinocchio run from rest until the transient has
    died out (`plan`), at the case's Omega, and against the derivation alone at the further `omegas`.

    Tolerances: the derivation against the theory within the neglected terms' first-order bound
    (`nonlinear_bound`, about theta^2) plus the transient left (`transient_left`) plus the peaks'
    sampling error; the engines against the derivation within `engine_tolerance` (their integrators'
    error; the transient and the sampling are the same in every source)."""
    start = time.perf_counter()
    theory = linearisation(case, settings["difference_step"])
    omegas = [case.params["Omega"]] + [w for w in settings["omegas"] if w != case.params["Omega"]]
    growth = float(np.max(theory.modes()[0].real))
    no_steady_state = f"the linear theory has no steady state: a mode grows at {growth:.3g} 1/s"
    rows, traces = [], {}
    for omega in omegas:
        X = theory.amplitudes(omega)
        if growth >= 0:  # nothing to settle to, and no time in which the transient would die out
            rows += [{"Omega": omega, "coordinate": coord, "unit": unit, "theory": abs(x), "status": "fail",
                      "why": no_steady_state} for coord, unit, x in zip(case.coords, case.spec["coord_units"], X)]
            continue
        if progress:
            progress(f"steady state at Omega = {omega:g} rad/s")
        variant = case if omega == case.params["Omega"] else case.with_params(Omega=omega)
        run_plan = plan(theory, omega, settings)
        sources = ("reference", "mujoco", "pinocchio") if variant is case else ("reference",)
        done = runs(variant, sources, run_plan, settings)
        bound = nonlinear_bound(variant, theory, omega)
        left = transient_left(theory, omega, run_plan["start"])
        for i, coord in enumerate(case.coords):
            measured = {}
            for source, (run, fail) in done.items():
                measured[source] = None if fail else amplitude(run.index.to_numpy(), run[coord].to_numpy(),
                                                               run_plan["start"])
            rows.append(_row(case, i, coord, omega, run_plan, abs(X[i]), measured, done, bound[i], left[i], settings))
        if variant is case:
            window = lambda run: run[run.index >= run_plan["start"]]
            traces = {"t": window(done["reference"][0]).index.to_numpy() if done["reference"][0] is not None else None,
                      "X": X, "omega": omega,
                      **{source: window(run)[list(case.coords)].to_numpy() for source, (run, fail) in done.items()
                         if fail is None}}
    data = pd.DataFrame(rows, columns=COLUMNS)
    findings = (_findings(case, theory, data, settings) if growth < 0 else
                [f"At rest, {no_steady_state} (eigenvalues {np.round(theory.modes()[0], 4).tolist()}): nothing was "
                 "run, and every amplitude fails."])
    sweep = np.linspace(*settings["sweep"], 400)
    curves = {"omega": sweep, "amplitudes": np.abs(np.array([theory.amplitudes(w) for w in sweep])),
              "undamped": theory.undamped_frequencies()}
    series = {"data": data, "curves": curves, "traces": traces, "coords": list(case.coords),
              "units": list(case.spec["coord_units"]), "title": case.title, "params": dict(case.params)}
    return study_result(case, "steady_state", "Steady-state amplitudes against the linear theory", settings, data,
                        _table(case, data), findings, series, start)


COLUMNS = ("Omega", "coordinate", "unit", "theory", "derivation", "mujoco", "pinocchio", "theory_error", "engine_error",
           "nonlinear_bound", "transient", "sampling", "tolerance", "engine_tolerance", "t_end", "output_step", "status",
           "why")  # of the study's data: one row per forcing frequency and coordinate


def _row(case, i, coord, omega, run_plan, theory_amplitude, measured, done, bound, left, settings):
    """One coordinate at one forcing frequency: the numbers and the verdict."""
    derivation = measured["reference"]
    engines = {s: a for s, a in measured.items() if s != "reference"}
    failed = [f"{s}: {describe(fail)}" for s, (_, fail) in done.items() if fail is not None]
    tolerance = bound + left + run_plan["sampling"]
    theory_error = None if derivation is None else derivation / theory_amplitude - 1
    engine_errors = [abs(a / derivation - 1) for a in engines.values() if a is not None and derivation is not None]
    engine_error = max(engine_errors) if engine_errors else None
    if failed:
        status = "unstable"
    elif abs(theory_error) <= tolerance and (engine_error is None or engine_error <= settings["engine_tolerance"]):
        status = "pass"
    else:
        status = "fail"
    return {"Omega": omega, "coordinate": coord, "unit": case.spec["coord_units"][i], "theory": theory_amplitude,
            "derivation": derivation, "mujoco": measured.get("mujoco"), "pinocchio": measured.get("pinocchio"),
            "theory_error": theory_error, "engine_error": engine_error, "nonlinear_bound": bound, "transient": left,
            "sampling": run_plan["sampling"], "tolerance": tolerance,
            "engine_tolerance": settings["engine_tolerance"] if engines else None,
            "t_end": run_plan["t_end"], "output_step": run_plan["output_step"], "status": status,
            "why": "; ".join(failed)}


def _table(case, data):
    def shown(row, column):
        scale, unit = DISPLAY[row["unit"]]
        return fmt(None if pd.isna(row[column]) else row[column] * scale, ".6g")
    return pd.DataFrame([{
        "Omega [rad/s]": f"{r['Omega']:g}",
        "coordinate": f"{r['coordinate']} [{DISPLAY[r['unit']][1]}]",
        "linear theory": shown(r, "theory"), "derivation": shown(r, "derivation"),
        "MuJoCo": shown(r, "mujoco"), "Pinocchio": shown(r, "pinocchio"),
        "derivation / theory - 1": fmt(r["theory_error"], "+.2e"), "tolerance": fmt(r["tolerance"], ".2e"),
        "engines / derivation - 1 (largest)": fmt(r["engine_error"], ".1e"),
        "tolerance (engines)": fmt(r["engine_tolerance"], ".0e"),
        "status": r["status"] + (f" ({r['why']})" if r["why"] else "")} for _, r in data.iterrows()])


def _findings(case, theory, data, settings):
    p = case.params
    omega = p["Omega"]
    X = np.abs(theory.amplitudes(omega))
    swing = X[case.coords.index(SWINGING)]
    here = data[data["Omega"] == omega]
    first = here.iloc[0]
    eigenvalues = theory.modes()[0]
    fastest = max(np.abs(eigenvalues).max(), omega)
    sigma = -eigenvalues.real.max()
    rk4 = (fastest * settings["mujoco_step"]) ** 4 * fastest / (120 * sigma)
    out = [f"Linear theory: the derivation linearised at rest (its mass matrix M0; K = -df/dq and C = -df/dv by "
           f"central differences of its forces with step {theory.step:g}, error ~ step^2 f''' / 6, measured "
           f"{theory.difference_error:.1e} of the largest entry with the step doubled), pushed by F0 = {p['F0']:g} N "
           f"on {PUSHED}: X = (K - Omega^2 M0 + i Omega C)^-1 F gives, at Omega = {omega:g} rad/s, " +
           ", ".join(f"|X_{c}| = {x * DISPLAY[u][0]:.6g} {DISPLAY[u][1]}"
                     for c, x, u in zip(case.coords, X, case.spec["coord_units"])) +
           f" ({SWINGING}^2 = {swing**2:.1e}). Undamped natural frequencies "
           f"{' and '.join(f'{w:.4g}' for w in theory.undamped_frequencies())} rad/s; "
           f"the slowest mode decays at sigma = {sigma:.4g} 1/s.",
           f"Runs from rest at q = 0 to t = {first['t_end']:.5g} s ({first['t_end'] * omega / (2 * math.pi):.1f} forcing "
           f"periods): the window of the last {settings['periods']:g} periods starts where e^(-sigma t) <= "
           f"{settings['settle']:g}, and the linear modes leave there at most "
           f"{here['transient'].max():.1e} of an amplitude. Output every {first['output_step'] * 1e3:g} ms, each "
           f"extreme refined by a parabola: sampling error <= (Omega d)^4 x 3/128 = {first['sampling']:.1e}. "
           f"The derivation and Pinocchio by DOP853 at rtol {settings['rtol']:g}, MuJoCo by its RK4 at "
           f"{settings['mujoco_step'] * 1e3:g} ms (omega h = {fastest * settings['mujoco_step']:.3f}: its steady-state "
           f"error ~ (omega h)^4 / 120 per radian over the decay time 1/sigma, {rk4:.0e}; the tolerance "
           f"{settings['engine_tolerance']:g} leaves room for it and for DOP853's)."]
    for _, r in here.iterrows():
        scale, unit = DISPLAY[r["unit"]]
        if pd.isna(r["derivation"]):
            out.append(f"{r['coordinate']} at Omega = {omega:g} rad/s: {r['status']} ({r['why']}).")
            continue
        engines = (f"MuJoCo and Pinocchio within {r['engine_error']:.1e} of it (tolerance {r['engine_tolerance']:g})"
                   if pd.notna(r["engine_error"]) else "the engines did not run")
        out.append(f"{r['coordinate']}'s steady amplitude {r['derivation'] * scale:.4g} {unit}: linear theory "
                   f"{r['theory'] * scale:.6g} {unit}, derivation {r['derivation'] * scale:.6g} "
                   f"({abs(r['theory_error']):.1e} {'above' if r['theory_error'] > 0 else 'below'}, "
                   f"{'inside' if abs(r['theory_error']) <= r['tolerance'] else 'OUTSIDE'} the tolerance "
                   f"{r['tolerance']:.1e}: the neglected cubic terms' first-order bound {r['nonlinear_bound']:.1e} "
                   f"= {r['nonlinear_bound'] / swing**2:.2f} {SWINGING}^2, plus transient and sampling); {engines}: "
                   f"{r['status']}.")
    others = data[data["Omega"] != omega]
    if len(others):
        out.append("The derivation alone at further forcing frequencies: " + "; ".join(
            f"Omega = {r['Omega']:g} rad/s, {r['coordinate']} {fmt(r['theory_error'], '+.1e')} from the theory "
            f"(tolerance {r['tolerance']:.1e}, {r['status']})" for _, r in others.iterrows()) + ".")
    failing = data[data["status"] != "pass"]
    out.append("Every amplitude agrees with the linear theory and across the sources within its tolerance."
               if failing.empty else
               f"{len(failing)} of {len(data)} amplitudes do not: " +
               ", ".join(f"{r['coordinate']} at Omega = {r['Omega']:g} rad/s ({r['status']})"
                         for _, r in failing.iterrows()) + ".")
    return out


def figure_steady_state(result, path, name):
    """Columns: the coordinates.  Rows: the linear theory's frequency response with the simulated amplitudes;
    the steady state over the measuring window; each source's departure from the linear theory there.  Returns
    the caption."""
    s = result.series
    coords, units, curves, traces, data = s["coords"], s["units"], s["curves"], s["traces"], s["data"]
    p = s["params"]
    fig, axes = panels(3, len(coords), 8.4)
    labels = {"reference": "derivation", "mujoco": "MuJoCo", "pinocchio": "Pinocchio"}
    markers = (("reference", "derivation", 7), ("mujoco", "mujoco", 5.5), ("pinocchio", "pinocchio", 4))
    for i, (coord, unit) in enumerate(zip(coords, units)):
        scale, shown = DISPLAY[unit]
        ax = axes[0, i]
        ax.plot(curves["omega"], curves["amplitudes"][:, i] * scale, color="black", lw=1.2,
                label="linear theory |X(Omega)|")
        for w in curves["undamped"]:
            ax.axvline(w, color="0.5", ls="--", lw=0.8)
        for source, column, size in markers:
            points = data[(data["coordinate"] == coord) & data[column].notna()]
            ax.plot(points["Omega"], points[column].astype(float) * scale, ls="none", ms=size, mfc="none", mew=1.4,
                    marker=SWEEP_STYLE[column]["marker"], color=SOURCE_STYLE[source]["color"],
                    label=f"{labels[source]}, simulated")
        ax.set_xlabel("forcing frequency Omega [rad/s]")
        ax.set_ylabel(f"amplitude of {coord} [{shown}]")
        ax.set_title(f"{coord}: frequency response")
        if traces.get("t") is None:  # the derivation did not run at the case's Omega: the table says why
            for ax in axes[1:, i]:
                ax.text(0.5, 0.5, "no run to show (see the table)", ha="center", va="center", transform=ax.transAxes)
            continue
        t, X, omega = traces["t"], traces["X"], traces["omega"]
        linear = (X[i] * np.exp(1j * omega * t)).real
        axes[1, i].plot(t, linear * scale, **SOURCE_STYLE["tight reference"], label="linear theory Re(X e^(i Omega t))")
        for source in labels:
            if source in traces:
                axes[1, i].plot(t, traces[source][:, i] * scale, **SOURCE_STYLE[source], label=f"{labels[source]}, run")
                axes[2, i].plot(t, (traces[source][:, i] - linear) * scale * 1e3, **SOURCE_STYLE[source])
        axes[1, i].set_ylabel(f"{coord} [{shown}]")
        axes[1, i].set_title(f"{coord}: steady state, Omega = {p['Omega']:g} rad/s")
        axes[2, i].set_ylabel(f"{coord} - linear theory [{FINE[unit]}]")
        axes[2, i].set_title(f"{coord} minus the linear theory")
        for ax in axes[1:, i]:
            ax.set_xlabel("time t [s]")
    fig.suptitle(title(name, f"steady state under F0 cos(Omega t), F0 = {p['F0']:g} N, from rest"))
    legend_below(fig, ncol=2)
    save(fig, path)
    failing = data[data["status"] != "pass"]
    return ("Top: each coordinate's steady amplitude against the forcing frequency, the linear theory's frequency"
            " response (line; dashed: the undamped natural frequencies) and the simulated amplitudes of every source"
            f" (markers). Middle: the steady state over the measuring window at Omega = {p['Omega']:g} rad/s, every"
            " source over the linear theory (wide pale line). Bottom: each source minus the linear theory, the"
            " cubic terms the linearisation leaves out, in which the sources coincide. "
            + ("Every amplitude agrees with the linear theory and across the sources within its tolerance."
               if failing.empty else f"{len(failing)} of {len(data)} amplitudes do not (see the table)."))


STUDIES = {"steady_state": Study(steady_state, figure_steady_state, (
    "rtol", "mujoco_step", "settle", "periods", "sampling", "difference_step", "engine_tolerance", "omegas", "sweep"))}
