"""Stage 2, the case: reading a case folder and evaluating its numbers at the parameters (folder: `Case`,
`load_case`), what a case file may hold (schema; its keys' meanings and docs/case-file.md in meanings, the
parameters' units in units, the files it may name in files), the scene it hands the engines (scene: an
dyncheck.case.scene.Scene), a case derived from a scene.xml and a plain equations.py (derived), the case's own
code loaded and bounded in time and memory (isolation).  Imports dyncheck.common, dyncheck.results and engines/
(which read the scene files and build the models)."""

__all__ = ["CASES_DIR", "Case", "case_names", "load_case"]


def __getattr__(name):
    # Loaded when first asked for, so that importing one module of the package (dyncheck.case.schema) does not load
    # the others.
    if name in __all__:
        from dyncheck.case import folder
        return getattr(folder, name)
    raise AttributeError(f"module 'dyncheck.case' has no attribute {name!r}")
