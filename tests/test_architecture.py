"""The architecture's rules, checked on the source (docs/architecture.md): no import cycle among the
project's modules, a stage of dyncheck/ imports only earlier stages, no module of dyncheck/ or engines/ is over
MAX_LINES lines, only engines/ imports the engines, the harness names no case, and a mechanism added from a folder outside
the tree runs without a change to dyncheck/ or engines/."""

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

import dyncheck
from dyncheck.case.folder import Case

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("dyncheck", "engines", "reference")


def modules():
    """{module name: path} of every module of the project's packages."""
    out = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


def imports(path, name, known):
    """The project's modules that the module `name` at `path` imports, anywhere in it (a function's
    import closes a cycle as surely as the module's own)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # relative: from the package, up level - 1
                base = ".".join(package.split(".")[:len(package.split(".")) - node.level + 1] + ([base] if base else []))
            # `from package import module` imports the module; `from module import name`, the module
            found |= {f"{base}.{alias.name}" if f"{base}.{alias.name}" in known else base for alias in node.names}
    return {module for module in found if module in known}


def test_no_module_imports_itself_back():
    known = modules()
    graph = {name: imports(path, name, known) for name, path in known.items()}
    cycles, path, done = [], [], set()

    def visit(name):
        if name in path:
            cycles.append(path[path.index(name):] + [name])
            return
        if name in done:
            return
        path.append(name)
        for other in sorted(graph[name]):
            visit(other)
        path.pop()
        done.add(name)

    for name in sorted(graph):
        visit(name)
    assert not cycles, "import cycles: " + "; ".join(" -> ".join(c) for c in cycles)


def test_the_walk_sees_a_cycle(tmp_path):
    """The test above can fail: two modules importing each other, one of them inside a function."""
    (tmp_path / "a.py").write_text("import b\n")
    (tmp_path / "b.py").write_text("def f():\n    from a import x\n")
    known = {"a": tmp_path / "a.py", "b": tmp_path / "b.py"}
    assert imports(known["a"], "a", known) == {"b"} and imports(known["b"], "b", known) == {"a"}


# The stages of dyncheck/, one package each, in the order of the data flow (docs/architecture.md); the modules at
# the top of dyncheck/ (the command line, `bench`) come after them all.  engines/ and reference/ are outside the order.
STAGES = ("common", "results", "case", "run", "checks", "studies", "pages")
MAX_LINES = 600


def stage(name):
    """The index of module `name`'s stage in STAGES (len(STAGES) for the commands), None outside dyncheck/."""
    parts = name.split(".")
    if parts[0] != "dyncheck":
        return None
    return STAGES.index(parts[1]) if len(parts) > 1 and parts[1] in STAGES else len(STAGES)


def upward(known):
    """(module, module it imports) where the second is of a later stage than the first."""
    return [(name, other) for name, path in sorted(known.items()) if stage(name) is not None
            for other in sorted(imports(path, name, known)) if stage(other) is not None and stage(other) > stage(name)]


def test_a_stage_imports_only_earlier_stages():
    known = modules()
    assert {name.split(".")[1] for name in known if name.count(".") == 1 and (ROOT / name.replace(".", "/")).is_dir()} \
        == set(STAGES), "a package of dyncheck/ that is no stage, or a stage that is no package"
    assert not upward(known), "imports of a later stage: " + "; ".join(f"{a} -> {b}" for a, b in upward(known))


def test_the_stage_order_sees_an_upward_import(tmp_path):
    """The test above can fail: a check importing a page, inside a function."""
    (tmp_path / "checks.py").write_text("def f():\n    from dyncheck.pages import report\n")
    (tmp_path / "report.py").write_text("from dyncheck.checks import runs\n")  # downward: allowed
    known = {"dyncheck.checks.runs": tmp_path / "checks.py", "dyncheck.pages.report": tmp_path / "report.py"}
    assert upward(known) == [("dyncheck.checks.runs", "dyncheck.pages.report")]


def test_no_module_of_the_harness_or_the_engines_is_over_max_lines():
    long = {str(path.relative_to(ROOT)): n for folder in ("dyncheck", "engines")
            for path in sorted((ROOT / folder).rglob("*.py")) if (n := len(path.read_text().splitlines())) > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines (split them by job): {long}"


@pytest.mark.parametrize("engine", ["mujoco", "pinocchio", "pydrake"])
def test_only_engines_import_the_engines(engine):
    importers = []
    for folder in ("dyncheck", "reference", "cases"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                    [node.module or ""] if isinstance(node, ast.ImportFrom) else []
                if any(n == engine or n.startswith(engine + ".") for n in names):
                    importers.append(str(path.relative_to(ROOT)))
    assert not importers, f"{engine} imported outside engines/ by {importers}"


def test_the_harness_names_no_case():
    names = dyncheck.case_names()
    spellings = names + [name.replace("_", " ") for name in names]  # "double_pendulum", "double pendulum"
    named = [(str(path.relative_to(ROOT)), name) for path in sorted((ROOT / "dyncheck").rglob("*.py"))
             for name in spellings if name in path.read_text().lower() or name in path.stem]
    assert not named, f"case names in dyncheck/: {named}"


def test_rendering_saved_results_needs_no_engine(results, tmp_path):
    """`report --from` in a process where importing MuJoCo or Pinocchio fails renders the same pages,
    byte for byte, as the report that saved the results (its figures included)."""
    full = tmp_path / "full"
    from dyncheck.pages.report import write_reports
    write_reports([results["rotating_particle"], results["spring_pendulum"]], full)
    again = tmp_path / "again"
    code = ("import sys; sys.modules['mujoco'] = sys.modules['pinocchio'] = None\n"
            "from dyncheck.cli import main\n"
            f"status = main(['report', '--from', {str(full / 'results')!r}, '--out', {str(again)!r}])\n"
            "assert not [m for m in sys.modules if m.startswith(('engines', 'mujoco', 'pinocchio')) and sys.modules[m]]\n"
            "sys.exit(status)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    files = lambda root: {p.relative_to(root): p.read_bytes() for p in root.rglob("*") if p.is_file()}
    assert files(again).keys() == files(full).keys()
    differ = [str(p) for p, data in files(full).items() if files(again)[p] != data]
    assert not differ, differ


@pytest.mark.full  # seconds of whole runs: `pytest -m full` (docs/speed.md)
def test_loading_the_cases_for_a_run_imports_no_matplotlib():
    """What `dyncheck run` does before its checks start (the command line and the checks imported, every case
    of cases/ and examples/ loaded with its models, studies and own study module) imports no matplotlib: only
    figures need it (dyncheck.common.style.pyplot), and it would be a quarter of a second of the run's start-up."""
    code = ("import sys\nfrom pathlib import Path\n"
            "from dyncheck.cli import select_cases\n"
            "import dyncheck.checks.runs\n"
            f"for folder in {[str(ROOT / 'cases'), str(ROOT / 'examples')]!r}:\n"
            "    select_cases([], [], Path(folder))\n"
            "print(sorted(m for m in sys.modules if m.partition('.')[0] == 'matplotlib'))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]", done.stdout


@pytest.mark.full
def test_a_whole_run_imports_no_matplotlib(tmp_path):
    """`dyncheck run` of every case imports no matplotlib, in its own process or in any of its workers (their
    imports reach the shared stderr through -X importtime)."""
    code = "import sys\nfrom dyncheck.cli import main\nsys.exit(main(['run']))\n"
    done = subprocess.run([sys.executable, "-X", "importtime", "-c", code], capture_output=True, text=True,
                          cwd=tmp_path)
    assert done.returncode == 0, done.stdout[-2000:]
    imported = [line.rpartition("|")[2].strip() for line in done.stderr.splitlines() if line.startswith("import time:")]
    assert "dyncheck.checks.runs" in imported  # the imports are reported
    assert not [m for m in imported if m.partition(".")[0] == "matplotlib"]


def doc_example():
    """The four files of docs/model-interface.md's complete example, from its code blocks in order: the
    example a user copies is the one this test runs."""
    text = (ROOT / "docs" / "model-interface.md").read_text()
    example = text[text.index("## A complete example"):]
    blocks = re.findall(r"```(python|toml|xml)\n(.*?)```", example, re.S)
    assert [kind for kind, _ in blocks] == ["python", "toml", "xml", "xml"], "the example's four files moved"
    return dict(zip(("equations.py", "case.toml", "scene.xml", "scene.urdf"), (code for _, code in blocks)))


@pytest.mark.full
def test_a_mechanism_from_a_folder_outside_the_tree_runs(tmp_path, capsys):
    """The documented example, a case folder made outside the checkout with its derivation in its own
    file: `dyncheck run --cases DIR` runs it and passes, and `report --from` renders it; nothing in
    dyncheck/ or engines/ names it.  With a term of the derivation wrong, the same run fails."""
    folder = tmp_path / "cases" / "oscillator"
    folder.mkdir(parents=True)
    files = doc_example()
    for name, text in files.items():
        (folder / name).write_text(text)
    assert Case(folder).derivation.__file__ == str(folder / "equations.py")
    from dyncheck.cli import main
    cases, saved = str(tmp_path / "cases"), str(tmp_path / "results")
    assert main(["run", "--cases", cases, "--results", saved]) == 0, capsys.readouterr().out
    out = capsys.readouterr().out
    assert "oscillator: " in out and "pass" in out and " fail" not in out
    assert main(["report", "--from", saved, "--out", str(tmp_path / "pages")]) == 0
    assert "# A.1 Mass on a spring" in (tmp_path / "pages" / "oscillator.md").read_text()
    wrong = files["equations.py"].replace('-self.p["k"] / self.p["m"]', '-self.p["k"] / 2.5')
    assert wrong != files["equations.py"]
    (folder / "equations.py").write_text(wrong)
    assert main(["run", "--cases", cases]) == 1


def test_nothing_points_outside_the_repository():
    """The repository carries its own contract: no file names the scaffolding it was built from."""
    tracked = subprocess.run(["git", "ls-files"], capture_output=True, text=True, cwd=ROOT).stdout.split()
    pointing = [name for name in tracked if name.endswith((".py", ".md", ".toml", ".xml", ".urdf"))
                and re.search(r"\.\./shared|DESIGN\.md", (ROOT / name).read_text(errors="replace"))]
    assert not pointing, pointing

