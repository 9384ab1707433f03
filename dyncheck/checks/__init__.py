"""Stage 4, the checks of a case, each yielding rows: `run_case` and the trajectories, energy and runaway
(runs), the pointwise comparisons and random parameter sets (pointwise), the book's programs and the findings'
localisation (programs, localise), the equations one by one (residuals) and their fit by terms (terms), the
convergence orders (convergence), the agreement horizon (horizon), the vibration analysis (vibration; its pieces
in linear, about a periodic motion in floquet), what the figures draw along the runs (drawings).  Imports the
earlier stages and engines/ (which the checks run)."""

PUBLIC = {"run_case": "runs", "unfinished": "runs", "parameter_sets": "pointwise", "validate_placeholders": "pointwise",
          "ENGINES": "pointwise"}  # name: its module
__all__ = list(PUBLIC)


def __getattr__(name):
    # Loaded when first asked for, as dyncheck.case's names are.
    if name in PUBLIC:
        from dyncheck.checks import pointwise, runs
        return getattr({"pointwise": pointwise, "runs": runs}[PUBLIC[name]], name)
    raise AttributeError(f"module 'dyncheck.checks' has no attribute {name!r}")
