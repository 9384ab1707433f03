"""1.10 spinning top: the Euler-angle singularity at zero nutation and the sleeping top."""

import math
import time
from fractions import Fraction

import numpy as np
import pandas as pd
from scipy.optimize import brentq

from dyncheck.case.folder import settings_of
from dyncheck.checks.linear import SAFETY
from dyncheck.common.style import legend_below, panels, save, title
from dyncheck.run.simulate import Unstable, attempt, describe, fastest_frequency, simulate
from dyncheck.studies.stability.common import EPS, Map, NotApplicable, Study, fmt, study_result


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
    return model.ball_joint_acceleration(euler.quaternion(angles), omega)


def euler_singularity(case, settings, progress=None):
    start = time.perf_counter()
    variant = case.with_params(**settings.get("overrides", {}))
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
    try:
        passes, no_passage = _passages(variant, settings, progress), []
    except NotApplicable as why:  # the rest of the study holds at any parameters
        passes, no_passage = [], [f"No passage through the upright: {why}."]

    ref = data[data["source"] == "reference (Euler angles)"]
    table = pd.DataFrame([{
        "nutation [rad]": f"{n:.0e}",
        "precession rate [rad/s]": f"{grp['precession_rate'].iloc[0]:.3g}",
        **{src: fmt(grp[grp["source"] == src]["error"].iloc[0], ".2e", none="not finite")
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
            f"{fmt(r['error'], '.1e', 'not finite')} at n = {r['nutation']:.0e}" for _, r in ref.iterrows())
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
    findings += no_passage
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
    return study_result(case, "euler_singularity", "The Euler-angle singularity at zero nutation", settings, data,
                        table, findings, series, start)


def _exact_angular_velocity(angles, rates):
    _, s, c = _rot_exact(angles)
    sn, cn, ss, cs = s[1], c[1], s[2], c[2]
    dp, dn, ds = (Fraction(float(x)) for x in rates)
    return [ss * sn * dp + cs * dn, cs * sn * dp - ss * dn, cn * dp + ds]


def _mujoco_tilt(model, q0, v0, t_end, dt):
    """MuJoCo's own RK4 from the book's state (q0, v0): times and the axis tilt (x, y components of the
    symmetry axis R e_z, from the quaternion: exact near upright, where Euler angles are not)."""
    quats = model.ball_joint_quaternions(q0, v0, t_end, dt, "RK4")
    steps = len(quats) - 1
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
    s_c2 = 4 * p["Ixx"] * p["m"] * p["g"] * p["h"] / p["Izz"] ** 2  # s_c^2, negative for a top hanging from its tip
    if spin**2 <= s_c2:
        raise NotApplicable(f"at the passages' spin {spin:.4g} rad/s the upright is unstable (below s_c = "
                            f"{math.sqrt(s_c2):.4g} rad/s): the top falls rather than swing through the vertical")
    omega0 = p["Izz"] * spin / (2 * p["Ixx"])
    mu = p["Izz"] * math.sqrt(spin**2 - s_c2) / (2 * p["Ixx"])
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
                                                 work=False, omega=fastest_frequency(case), **kwargs))
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


def maxwell_klein(p):
    """The least spin of a stable upright top, s_c = 2 sqrt(Ixx m g h) / Izz (Ixx about the tip)."""
    return 2 * math.sqrt(p["Ixx"] * p["m"] * p["g"] * p["h"]) / p["Izz"]


def upright_run(case, settings, trail):
    """stays_up(s): whether MuJoCo's top, started `start_nutation` from upright with only the spin s, keeps its
    nutation within `bound` for `horizon` seconds; each run is added to `trail`."""
    n0, bound, T = settings["start_nutation"], settings["bound"], settings["horizon"]
    dt, method = settings["mujoco_step"], settings.get("method", "mujoco:RK4")
    model = case.model("mujoco")

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
    return stays_up


def least_spin(stays_up, criterion, settings):
    """Bisection on the spin between `bracket` times the criterion, to `resolution` of it: (falls at, stays up
    at, whether the bracket held)."""
    lo, hi = settings["bracket"][0] * criterion, settings["bracket"][1] * criterion
    bracket_ok = not stays_up(lo) and stays_up(hi)
    while bracket_ok and hi - lo > settings["resolution"] * criterion:
        mid = 0.5 * (lo + hi)
        if stays_up(mid):
            hi = mid
        else:
            lo = mid
    return lo, hi, bracket_ok


def sleeping_top(case, settings, progress=None):
    """The least spin of a stable upright top, by bisection with MuJoCo (quaternions: no singularity upright)."""
    start = time.perf_counter()
    variant = case.with_params(**settings.get("overrides", {}))
    p = variant.params
    if not p["m"] * p["g"] * p["h"] > 0:
        raise NotApplicable(f"m g h = {p['m'] * p['g'] * p['h']:.3g} N m: with its centre of mass at or below the tip "
                            "the top needs no spin to stay upright, so there is no least spin to find")
    criterion = maxwell_klein(p)
    n0, bound, T = settings["start_nutation"], settings["bound"], settings["horizon"]
    dt, method = settings["mujoco_step"], settings.get("method", "mujoco:RK4")
    trail = []
    stays_up = upright_run(variant, settings, trail)
    if progress:
        progress("sleeping top")
    lo, hi, bracket_ok = least_spin(stays_up, criterion, settings)
    # The exact motion's first integrals at this bound and horizon (`top_nutation`): the spin the bisection
    # should find.  Below it the top reaches the bound within T.
    falls = lambda s: top_nutation(p, s, n0, T)[0] >= bound
    f_lo, f_hi = 0.5 * criterion, 1.5 * criterion
    while f_hi - f_lo > 1e-7 * criterion:
        mid = 0.5 * (f_lo + f_hi)
        f_lo, f_hi = (mid, f_hi) if falls(mid) else (f_lo, mid)
    finite = 0.5 * (f_lo + f_hi)
    turning = top_nutation(p, finite, n0, math.inf)
    upright = upright_eigenvalues(variant, criterion)
    either = {side: stays_up(upright["threshold"]["pinocchio"] * (1 + side * EITHER_SIDE)) for side in (+1, -1)}
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
        f"({criterion / (2 * math.pi):.3g} rev/s) for this top. The book states no such criterion; its "
        "parameter names are those of the formula (Ixx about the tip O, Izz about the axis).",
        f"Numerically (MuJoCo, {method} at dt = {dt:g} s, no resisting moment: Mz = 0 overrides the case's "
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
        if bracket_ok else "No comparison (the bracket failed).",
        "From the eigenvalues (the book's step 16): both engines linearise the upright top spinning at s in their own "
        "coordinates (the ball joint's rotation vector and angular velocity; ball_joint_linearisation), and the "
        "largest real part of the eigenvalues is the tilt's growth rate.  It becomes positive below "
        + ", ".join(f"{s_:.9g} rad/s ({NAMES[source]}, {(s_ / criterion - 1):+.1e} of s_c)"
                    for source, s_ in upright["threshold"].items())
        + f"; across 0.5 to 1.5 s_c it equals the linear theory's Izz sqrt(s_c^2 - s^2) / (2 Ixx) to "
        f"{upright['worst']:.1e} of its largest value.  MuJoCo's runs {EITHER_SIDE:.0%} either side of it: "
        f"{'stays up' if either[+1] else 'falls'} above, {'stays up' if either[-1] else 'falls'} below"
        + (", as the eigenvalues say." if either[+1] and not either[-1] else ": AGAINST the eigenvalues.")]
    series = {"trail": data, "growth": upright["growth"], "criterion": criterion, "finite": finite, "lo": lo, "hi": hi, "n0": n0, "bound": bound,
              "horizon": T, "params": dict(p), "method": method, "dt": dt}
    return study_result(case, "sleeping_top", "The sleeping top: least spin of a stable upright top", settings,
                   data, summary, findings, series, start)


EITHER_SIDE = 0.02  # MuJoCo's runs either side of the eigenvalues' threshold, relative
NAMES = {"mujoco": "MuJoCo", "pinocchio": "Pinocchio"}


def upright_eigenvalues(variant, criterion):
    """The upright top's linearisation by each engine (its own coordinates): the largest real part of the
    eigenvalues at spins 0.5 to 1.5 s_c against the linear theory's growth rate, and each engine's threshold by
    bisection.  A real part counts as positive beyond SAFETY sqrt(error ||A||): at the threshold the two tilt
    eigenvalues meet as a double one, which an error E splits by up to sqrt(E ||A||)."""
    p = variant.params
    upright = np.array([1.0, 0.0, 0.0, 0.0])

    def largest_real(source, spin):
        a, error = variant.model(source).ball_joint_linearisation(upright, np.array([0.0, 0.0, spin]))
        real = np.max(np.linalg.eigvals(a).real)
        return real, SAFETY * math.sqrt(error * np.linalg.norm(a))

    spins = np.linspace(0.5, 1.5, 41) * criterion
    theory = p["Izz"] * np.sqrt(np.maximum(criterion**2 - spins**2, 0.0)) / (2 * p["Ixx"])
    growth = pd.DataFrame({"spin": spins, "theory": theory,
                           **{source: [largest_real(source, x)[0] for x in spins] for source in NAMES}})
    worst = max(np.max(np.abs(growth[source] - theory)) for source in NAMES) / np.max(theory)
    threshold = {}
    for source in NAMES:
        lo, hi = 0.8 * criterion, 1.25 * criterion  # unstable, stable
        while hi - lo > 1e-12 * criterion:
            mid = 0.5 * (lo + hi)
            real, allowed = largest_real(source, mid)
            lo, hi = (mid, hi) if real > allowed else (lo, mid)
        threshold[source] = 0.5 * (lo + hi)
    return {"growth": growth, "worst": worst, "threshold": threshold}


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


def figure_euler_singularity(result, path, name):
    """The angular acceleration's error against the nutation, and runs through the near-upright; returns the caption."""
    s = result.series
    rows = s["rows"]
    passes = [p for p in s["passes"] if p.get("status") == "ok"]
    fig, axes = panels(2 if passes else 1, 1, 8.8 if passes else 4.4)
    axes = axes[:, 0]
    ax = axes[0]
    styles = {"reference (Euler angles)": dict(color="tab:red", marker="o", lw=1.5),
              "truth at the rounded Euler rates": dict(color="tab:orange", marker="v", lw=1, ls="--"),
              "mujoco (quaternion)": dict(color="tab:green", marker="s", lw=1, mfc="none"),
              "pinocchio (quaternion)": dict(color="tab:blue", marker="x", lw=1)}
    floor = 1e-18
    for source, group in rows.groupby("source", sort=False):
        err = group["error"].astype(float).fillna(np.inf)
        engine, _, how = source.partition(" ")
        ax.plot(group["nutation"], np.clip(err, floor, 1e3), label=" ".join(filter(None, (NAMES.get(engine, engine), how))),
                **styles.get(source, {}))
    ax.axhline(EPS, color="0.5", ls=":", lw=1, label=f"machine epsilon, {EPS:.1e}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.invert_xaxis()
    ax.set_xlabel("nutation [rad] (toward upright ->)")
    ax.set_ylabel("relative error of the\nangular acceleration [1]")
    ax.set_title("the same physical state: body angular acceleration\n(errors below 1e-18 drawn at 1e-18)")
    ax.grid(True, which="both")
    if passes:
        ax = axes[1]
        colors = ["tab:red", "tab:purple", "tab:brown", "tab:pink"]
        for p, color in zip(passes, colors):
            for key, ls, label in (("dop853", "-", "DOP853"), ("rk4", "--", "fixed RK4")):
                x = p.get(key, {})
                if x.get("status") == "ok":
                    ax.plot(p["t"], np.clip(x["error"], floor, np.pi), color=color, ls=ls, lw=1.1,
                            label=f"Euler angles, {label}, closest {p['closest']:.0e} rad")
                elif x.get("fail", {}).get("t") is not None:
                    ax.plot([x["fail"]["t"]], [1.0], marker="X", ms=9, color=color, ls="none",
                            label=f"Euler angles, {label}, closest {p['closest']:.0e} rad: blows up "
                                  f"at t = {x['fail']['t']:.3g} s")
        ax.plot(passes[0]["t"], np.maximum(passes[0]["error_mj"], floor), color="tab:green", lw=1.5, ls="-.",
                label="MuJoCo RK4 (quaternion) vs its half-step twin")
        ax2 = ax.twinx()
        closest = min(passes, key=lambda p: p["closest"])
        ax2.plot(closest["t"], closest["nutation"], color="0.55", lw=0.8,
                 label=f"nutation of the closest passage ({closest['closest']:.0e} rad), right axis")
        ax2.set_yscale("log")
        ax2.set_ylabel("nutation [rad], closest\npassage (grey)", color="0.4")
        ax.set_yscale("log")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("axis direction error\nagainst MuJoCo [rad]")
        ax.set_title(f"a top whose axis swings past the vertical, {len(passes)} aims")
        ax.grid(True, which="both")
        ax.set_ylim(floor / 10, 10)  # an axis's direction is off by pi rad at most
    fig.suptitle(title(name, "the Euler-angle equations near zero nutation"))
    legend_below(fig, ncol=1)
    save(fig, path)
    worst = rows[rows["source"] == rows["source"].iloc[0]].astype({"error": float}).sort_values("nutation")
    errors = ("the relative error of the body angular acceleration of one physical state, as the nutation goes to"
              " zero (toward upright, to the right), from the book's Euler-angle equations and from the engines fed the"
              f" same state as a quaternion: the Euler-angle error grows like 1/n^2, to {worst['error'].iloc[0]:.1g} at"
              f" n = {worst['nutation'].iloc[0]:.0e} rad, the engines' stays at rounding.")
    if not passes:  # not applicable at these parameters: the study's findings say why
        return errors[0].upper() + errors[1:]
    return (f"Top: {errors} Bottom: runs through the near-upright, the axis direction against MuJoCo's: an adaptive"
            " integrator follows the singularity by shrinking its steps, a fixed-step one blows up (X) when the axis"
            " passes closest (grey: the nutation of the closest passage).")


def figure_sleeping_top(result, path, name):
    """The largest nutation against the spin, and the engines' growth rates; returns the caption."""
    s = result.series
    trail = s["trail"]
    fig, axes = panels(2, 1, 8.0, height_ratios=[5.2, 3])
    ax, eig = axes[:, 0]
    spins = np.linspace(0.985 * s["criterion"], 1.01 * s["criterion"], 160)
    reached = np.array([top_nutation(s["params"], x, s["n0"], s["horizon"])[0] for x in spins])
    ax.plot(spins, reached, color="0.35", lw=1.8,
            label=f"first integrals (exact): largest nutation within {s['horizon']:g} s")
    ran = trail[trail["status"] == "ran"]
    for stable, marker, color, label in ((True, "o", "tab:green", "MuJoCo: stays below the bound"),
                                         (False, "x", "tab:red", "MuJoCo: falls past the bound")):
        g = ran[ran["stable"] == stable]
        ax.plot(g["spin"], g["max_nutation"], ls="none", marker=marker, color=color, ms=6, mew=1.5, label=label)
    ax.axvline(s["criterion"], color="black", ls="--",
               label=f"criterion s_c = 2 sqrt(Ixx m g h) / Izz = {s['criterion']:.4g} rad/s")
    ax.axvline(s["finite"], color="tab:blue", ls=":", label=f"threshold for this bound and horizon: {s['finite']:.5g}")
    ax.axhline(s["bound"], color="tab:orange", ls=":", label=f"bound {s['bound']:g} rad")
    ax.set_yscale("log")
    ax.set_xlim(spins[0], spins[-1])
    ax.set_xlabel("spin s [rad/s]")
    ax.set_ylabel("largest nutation over the run [rad]")
    ax.set_title(f"started {s['n0']:g} rad from upright with only the spin, Mz = 0, {s['horizon']:g} s;\n"
                 f"MuJoCo {s['method']} at dt = {s['dt']:g} s")
    ax.grid(True, which="both")
    growth = s["growth"]
    eig.plot(growth["spin"], growth["theory"], color="0.35", lw=1.8, label="linear theory: Izz sqrt(s_c^2 - s^2) / (2 Ixx)")
    for source, marker, color in (("mujoco", "^", "tab:green"), ("pinocchio", "s", "tab:blue")):
        eig.plot(growth["spin"], growth[source], ls="none", marker=marker, mfc="none", color=color,
                 label=f"{NAMES[source]}: largest real part of its linearisation's eigenvalues")
    eig.axvline(s["criterion"], color="black", ls="--")
    eig.set_xlabel("spin s [rad/s]")
    eig.set_ylabel("tilt growth rate [1/s]")
    eig.set_title("the upright top linearised by each engine in its own coordinates (step 16)")
    fig.suptitle(title(name, "the sleeping top's least spin"))
    legend_below(fig, ncol=1)
    save(fig, path)
    return (f"Top: the largest nutation a top started {s['n0']:g} rad from upright with only its spin reaches within"
            f" {s['horizon']:g} s, against the spin: from the first integrals (exact, grey line) and MuJoCo's runs"
            " (markers: stays up or falls). It stands above the criterion"
            f" s_c = 2 sqrt(Ixx m g h) / Izz = {s['criterion']:.4g} rad/s (dashed); just below it the exact motion"
            f" wobbles out slowly, so within this horizon and bound it falls only below {s['finite']:.5g} rad/s"
            " (dotted). Bottom: the tilt's growth rate from each engine's linearisation of the upright top against the"
            " linear theory; it turns positive below s_c.")


STUDIES = {
    "euler_singularity": Study(euler_singularity, figure_euler_singularity, (
        "nutation", "precession", "spin_angle", "spin", "transverse", "direction", "passage_spin", "start_nutation",
        "miss", "passage_horizon", "passage_output", "mujoco_step", "rtol")),
    "sleeping_top": Study(sleeping_top, figure_sleeping_top, (
        "start_nutation", "bound", "horizon", "mujoco_step", "bracket", "resolution")),
}


# -- the campaign's map: the sleeping top's least spin over the inertia ratio and the height -------------------------

MAP_RATIO = (0.3, 0.75)  # Izz / Ixx, Ixx at the case's: every cell realisable up to h = 0.055 m (A + B >= C)
MAP_HEIGHT = (0.02, 0.055)  # h, m


def map_grid(case, n):
    return "Izz / Ixx", np.linspace(*MAP_RATIO, n), "h [m]", np.linspace(*MAP_HEIGHT, n)


def map_cell(case, ratio, h):
    """The least spin at which MuJoCo's upright top stays up (`least_spin`, the sleeping_top study's settings), against
    the Maxwell-Klein criterion; none where the inertias are no rigid body's or the bracket fails."""
    settings = settings_of(case, "sleeping_top")
    try:
        variant = case.with_params(**settings.get("overrides", {}), Izz=ratio * case.params["Ixx"], h=h)
    except ValueError as error:  # inertias that no rigid body has
        return {"value": math.nan, "theory": math.nan, "status": f"not physical: {error}"}
    criterion = maxwell_klein(variant.params)
    lo, hi, bracket_ok = least_spin(upright_run(variant, settings, []), criterion, settings)
    return {"value": 0.5 * (lo + hi) if bracket_ok else math.nan, "theory": criterion,
            "status": "measured" if bracket_ok else "bracket failed"}


MAPS = {"sleeping_top": Map("the sleeping top's least spin over the inertia ratio and the height", map_grid, map_cell,
                            "least spin [rad/s]", "Maxwell-Klein 2 sqrt(Ixx m g h) / Izz")}
