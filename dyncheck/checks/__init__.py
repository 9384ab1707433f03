"""Stage 4, the checks of a case: `run_case` and its rows (runs), the equations one by one (residuals) and their
fit by terms (terms), the localisation of a finding (localise), the vibration analysis about an equilibrium
(vibration).  Imports the earlier stages (dyncheck.common, dyncheck.results, dyncheck.case, dyncheck.run) and
engines/ (which the checks run)."""

PUBLIC = {"run_case": "runs", "unfinished": "runs", "parameter_sets": "pointwise", "validate_placeholders": "pointwise",
          "ENGINES": "pointwise"}  # name: its module
__all__ = list(PUBLIC)


def __getattr__(name):
    # Loaded when first asked for, as dyncheck.case's names are.
    if name in PUBLIC:
        from dyncheck.checks import pointwise, runs
        return getattr({"pointwise": pointwise, "runs": runs}[PUBLIC[name]], name)
    raise AttributeError(f"module 'dyncheck.checks' has no attribute {name!r}")
