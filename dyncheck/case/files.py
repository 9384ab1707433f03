"""The files a case file may name, checked before anything is read or run: its own (`own_file`, inside its
folder) and its derivation (`derivation_file`: a file of its folder, or a module of the package's reference/)."""

from pathlib import Path

from dyncheck.common.messages import field_error

# The package's own derivations, the one place outside a case's folder that its `derivation` may name.
REFERENCE = Path(__file__).resolve().parents[2] / "reference"


def own_file(folder, name, field, file):
    """The file `name` that the case file's `field` gives, as a path inside the case's `folder` (symbolic links
    and .. resolved): a case file names only files of its own folder, so that reading a case runs no code
    from elsewhere.  ValueError for a path that leaves it; whether the file is there is the caller's to say."""
    path = (Path(folder) / name).resolve()
    if not path.is_relative_to(Path(folder).resolve()):
        raise field_error(file, field, name, f"is not a file of the case's folder {folder} (it is {path}): a case file "
                     "names only files of its own folder")
    return path


def derivation_file(derivation, folder, file):
    """The file of the case's equations, checked before anything is imported: a .py file in the case's
    `folder` (own_file), or `reference.<name>`, the package's own reference/<name>.py (never any other
    module: finding one would import its parent packages, and loading it runs whatever is installed)."""
    if derivation.endswith(".py"):
        path = own_file(folder, derivation, "derivation", file)
        where = "no file in the case folder"
    else:
        package, _, name = derivation.partition(".")
        if package != REFERENCE.name or not name.isidentifier():
            raise field_error(file, "derivation", derivation, f"is neither a module of the package's {REFERENCE.name}/ "
                         f"({REFERENCE.name}.<name>) nor a path ending in .py of the case's folder")
        path, where = REFERENCE / f"{name}.py", f"no module of the package's {REFERENCE.name}/"
    if not path.is_file():
        raise field_error(file, "derivation", derivation, f"names {where} (where the case's equations live)")
    return path
