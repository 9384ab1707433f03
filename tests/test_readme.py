"""The README's quick start says what a newcomer needs, truly; its links and the docs' links resolve."""

import re
import subprocess
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text()
LINK = re.compile(r"\]\(([^)\s]+)\)")


def anchor(heading):
    """GitHub's anchor of a Markdown heading."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


@pytest.mark.parametrize("page", [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))],
                         ids=lambda page: page.relative_to(ROOT).as_posix())
def test_every_relative_link_resolves(page):
    """Links into the checkout (the README's moved detail in docs/, docs' links back) lead to a file, and an
    anchor to one of its headings."""
    broken = []
    for target in LINK.findall(page.read_text()):
        if re.match(r"[a-z]+:", target):  # https:, mailto:
            continue
        path, _, fragment = target.partition("#")
        linked = (page.parent / path).resolve() if path else page
        if not linked.exists():
            broken.append(target)
        elif fragment and linked.is_file() and fragment not in {
                anchor(line.lstrip("#")) for line in linked.read_text().splitlines() if line.startswith("#")}:
            broken.append(target)
    assert not broken, f"{page.relative_to(ROOT)}: links that lead nowhere: {broken}"


def test_the_quick_start_names_the_python_that_pyproject_requires():
    required = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["requires-python"]
    version = re.fullmatch(r">=\s*3\.(\d+)", required).group(1)
    assert f"Python 3.{version} or newer" in README
    assert "reports/index.md" in README


def test_the_readme_has_exactly_two_set_up_commands_and_ci_runs_its_test_command():
    commands = re.findall(r"^    (\S.*)$", README, re.M)  # the indented blocks a newcomer pastes
    assert commands == ["pip install -e . && dyncheck report && dyncheck report --cases examples --out reports/examples",
                        "pip install -e '.[test]' && pytest"]
    ci = (ROOT / ".ci" / "run").read_text()
    assert "pip install -e '.[test]'" in ci and "\npytest\n" in ci


def test_the_count_of_timing_files_that_report_rewrites_is_the_reports_own():
    """`dyncheck report` (both README commands) rewrites the files named for their timings; a campaign's (under
    reports/campaigns/, from `dyncheck campaign`) are not its."""
    timing = [path for path in (ROOT / "reports").rglob("*timing*") if "campaigns" not in path.parts]
    assert f"the {len(timing)} named `*timing*`" in README


def test_a_report_under_set_is_ignored_by_git():
    """`dyncheck report --set k=500` writes reports-k=500/ into the current folder (the checkout, by the README)."""
    ignored = subprocess.run(["git", "check-ignore", "--no-index", "reports-k=500/index.md",
                              "reports-m2=0.5-l2=0.3/figures/x.png"], cwd=ROOT, capture_output=True, text=True)
    assert ignored.stdout.split() == ["reports-k=500/index.md", "reports-m2=0.5-l2=0.3/figures/x.png"]
    assert "`reports-k=500/`" in README
