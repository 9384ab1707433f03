"""Stage 4, the checks of a case: `run_case` and its rows (runs), the equations one by one (residuals) and their
fit by terms (terms), the localisation of a finding (localise), the vibration analysis about an equilibrium
(vibration).  Imports the earlier stages (dyncheck.common, dyncheck.results, dyncheck.case, dyncheck.run) and
engines/ (which the checks run)."""

__all__ = ["ENGINES", "parameter_sets", "run_case", "unfinished", "validate_placeholders"]


def __getattr__(name):
    # Loaded when first asked for, as dyncheck.case's names are.
    if name in __all__:
        from dyncheck.checks import runs
        return getattr(runs, name)
    raise AttributeError(f"module 'dyncheck.checks' has no attribute {name!r}")
