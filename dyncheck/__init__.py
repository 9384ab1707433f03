"""dyncheck: the worked examples of 'Dynamics of Machines' ch. 1 against MuJoCo and Pinocchio."""

__all__ = ["Case", "case_names", "load_case"]


def __getattr__(name):
    # Loaded when first asked for, not on `import dyncheck`: the console command (dyncheck.__main__) imports the
    # package before the heavy modules, so that Ctrl-C during their import ends it in one line.
    if name in __all__:
        from dyncheck import case
        return getattr(case, name)
    raise AttributeError(f"module 'dyncheck' has no attribute {name!r}")
