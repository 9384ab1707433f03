"""A case file names only files of its own folder, or the package's own reference/ modules: anything else
in `derivation` or `[stability] module` is refused (exit 2, one line naming the file and the field)
before anything is imported, so reading a case never runs code from elsewhere."""

import pytest

from dyncheck.cli import main
from test_architecture import doc_example

# A module that leaves a marker beside itself when it is executed.
EVIL = "from pathlib import Path\n(Path(__file__).parent / 'MARKER').write_text('executed')\n"


@pytest.fixture
def tutorial(tutorial, tmp_path):
    """The guide's two-file case (conftest), and an evil file beside its cases/ folder."""
    (tmp_path / "evil.py").write_text(EVIL)
    return tutorial


def refused(tmp_path, capsys, command, field):
    status = main([command, "--cases", str(tmp_path / "cases")])
    err = capsys.readouterr().err
    assert status == 2 and len(err.splitlines()) == 1, err
    assert f"{field} = " in err and "is not a file of the case's folder" in err, err
    assert not (tmp_path / "MARKER").exists(), "the file outside the case folder was executed"
    return err


@pytest.mark.parametrize("command", ["run", "list"])
@pytest.mark.parametrize("toml, link", [
    ('derivation = "{evil}"', None),  # an absolute path
    ('derivation = "../../evil.py"', None),
    ('derivation = "sub/../../../evil.py"', None),
    ('derivation = "link.py"', "link.py"),  # a symbolic link in the folder to a file outside it
    ('[stability]\nmodule = "../../evil.py"', None),
    ('[stability]\nmodule = "studies.py"', "studies.py"),
])
def test_a_file_outside_the_case_folder_is_refused_unrun(tutorial, tmp_path, capsys, command, toml, link):
    if link:
        (tutorial / link).symlink_to(tmp_path / "evil.py")
    (tutorial / "case.toml").write_text(toml.format(evil=tmp_path / "evil.py") + "\n")
    err = refused(tmp_path, capsys, command, "stability.module" if "stability" in toml else "derivation")
    assert str(tutorial / "case.toml") in err


@pytest.mark.parametrize("command", ["run", "list"])
def test_an_equations_file_linked_from_outside_is_refused_unrun(tutorial, tmp_path, capsys, command):
    """A two-file case (no case.toml) whose equations.py is a symbolic link to a file elsewhere: the message
    names the file that exists, not a case.toml."""
    (tutorial / "equations.py").unlink()
    (tutorial / "equations.py").symlink_to(tmp_path / "evil.py")
    err = refused(tmp_path, capsys, command, "derivation")
    assert err.startswith(f"dyncheck: error: {tutorial / 'equations.py'}: "), err


@pytest.mark.parametrize("derivation", ["this", "os", "evil", "evilpackage.sub", "reference.evil", "dyncheck.cli"])
def test_a_derivation_that_is_not_the_package_s_reference_is_refused_unimported(tmp_path, capsys, monkeypatch,
                                                                                  derivation):
    """Any module but reference.<name>, installed or not: not imported (finding an installed one would import
    its parent packages: `evilpackage/__init__.py` here)."""
    (tmp_path / "evil.py").write_text(EVIL)
    (tmp_path / "evilpackage").mkdir()
    (tmp_path / "evilpackage" / "__init__.py").write_text(EVIL.replace("parent", "parent.parent"))
    monkeypatch.syspath_prepend(str(tmp_path))
    folder = tmp_path / "cases" / "oscillator"
    folder.mkdir(parents=True)
    for file, text in doc_example().items():
        (folder / file).write_text(text.replace('derivation = "equations.py"', f'derivation = "{derivation}"'))
    status = main(["list", "--cases", str(tmp_path / "cases")])
    out, err = capsys.readouterr()
    assert status == 2 and len(err.splitlines()) == 1, err
    assert f"case.toml: derivation = '{derivation}' " in err and "reference/" in err, err
    assert not (tmp_path / "MARKER").exists() and "Beautiful is better than ugly" not in out


def test_a_file_of_the_case_folder_in_a_subfolder_is_taken(tutorial, tmp_path, capsys):
    """Confinement is by where a path resolves, not by its spelling: a subfolder's file, named with a .. that
    stays inside, loads."""
    (tutorial / "equations").mkdir()
    (tutorial / "equations.py").rename(tutorial / "equations" / "cart.py")
    (tutorial / "case.toml").write_text('derivation = "equations/../equations/cart.py"\n')
    assert main(["list", "--cases", str(tmp_path / "cases")]) == 0, capsys.readouterr().err
