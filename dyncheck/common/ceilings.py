"""Ceilings of the checks' tolerances.  Above its ceiling a comparison proves nothing: a row whose
derived tolerance exceeds it is `inconclusive` (never `pass`; the run exits 1), and a case file that
asks for a tolerance above it is refused on load (exit 2).  Each ceiling's argument is beside it."""

import numpy as np

EPS = np.finfo(float).eps
ROUNDING_FLOOR = 1e3 * EPS  # rounding over a run: a thousand ulps of the quantity's scale

# Pointwise comparisons (and the random parameter sets, and a listing's formulas at the same states)
# compare exact evaluations of the same quantity: rounding costs a few hundred eps (~1e-13) and the
# scenes' modelling residues (placeholder masses and inertias) are argued below 1e-10 in each case
# file.  A tolerance of 1e-6 is 1e4 times the largest of those; above it a term of the equations
# could be missing and still pass.
POINTWISE = 1e-6

# Trajectories and energy balances are judged against `safety` times the run's own error estimate
# (its difference from a tighter twin).  That estimate assumes the run's error grows linearly with a
# perturbation; beyond about 1e-3 of a quantity's scale it does not (where the book's chaotic
# example's difference stops growing linearly: [stability.lyapunov] in its case file), and neither the
# estimate nor a comparison built on it means anything.
RUN = 1e-3

# The safety factor on an error estimate: the estimates are first-order accurate in the error, so a
# factor of 10 covers them (the case files' choice); one above 100 says the estimate is not trusted,
# and then the check built on it is not either.
SAFETY = 100.0

# Observed orders of convergence are integers: an allowance of half an order cannot tell an order
# from its neighbour.
CONVERGENCE = 0.5

# The book's printed numbers against its own formulas: a number printed to two significant digits is
# exact to 5e-2; a tolerance above that cannot tell a printing error from the printed rounding.
DATA = 5e-2

# A listing's run against the exact motion: a printed figure shows a curve to about 1 % of its axis,
# so a run that strays by more than 1e-2 of a coordinate's scale draws a different curve.  This is
# the tolerance of those rows as well as their ceiling; the listing's own integrator error estimate
# says, in the row, whether its integrator or its formulas stray.
LISTING = 1e-2

# MuJoCo holds the prescribed motions by a large armature A; they drift by torque x time / A.  What the
# drift changes in the motion is measured (the run with A halved, dyncheck.checks.runs.approximations_effect)
# and allowed in the trajectory and energy rows; that measurement is first order in the drift, its error
# second order: a drift within 1e-6 of the run's largest rate keeps it below a millionth of the effect.
DRIVEN_RATE = 1e-6  # of the largest rate of the run, and at least of 1 rad/s (or m/s)

# A frequency measured in a run from an equilibrium displaced along one mode differs from the linear one by
# the nonlinear shift (quadratic in the amplitude) and the integrator's error.  A wrong term of the
# linearised equations moves a frequency by about half its share of the stiffness; an allowance of 1e-4 of the
# frequency still sees any term above 2e-4 of it.  Above it, the amplitude is too large to test the linear
# frequency.
MOTION = 1e-4

# Figure ranges are inside/outside: any excess over the book's printed axis is outside.
FIGURE = 0.0

# The limits of one run (dyncheck.run.simulate), which the case file's schema also keeps.
MAX_STEPS = 10**6  # any one run: a fixed-step run of this length costs 5 s in MuJoCo, 20-400 s in Python
# The least rtol an adaptive run may ask for.  scipy's solvers raise an rtol below 100 machine epsilons to
# that (scipy.integrate._ivp.common.validate_tol, with only a warning): a run asked for less is not the run it
# says, and a tight twin asked for less is its twin's own run, whose difference then estimates an error of 0
# (rtol 1e-14 with tight_rtol 1e-15 passed every trajectory row so).  With atol = rtol (_scipy) a smaller one
# would also ask for an absolute error below the rounding of a state of order 1 (eps), which no double-
# precision step can meet: its step sizes collapse (rtol 1e-300 made every run unstable).
LEAST_RTOL = 100 * EPS
