"""The cache of tight solutions (dyncheck/run/cache.py): what it returns is what simulate computes, bit for bit,
and a change in anything the solution depends on is a new key, never the old entry."""

import importlib
import shutil
import sys

import pandas as pd
import pytest

import dyncheck
from dyncheck.run import cache
from dyncheck.run.simulate import simulate

CASES = dyncheck.case.folder.CASES_DIR
OPTIONS = dict(rtol=1e-12, output_step=1e-3, work=False)


@pytest.fixture
def folder(tmp_path, monkeypatch):
    monkeypatch.setenv("DYNCHECK_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(cache, "enabled", True)
    return tmp_path / "cache"


def solve(case, t_end=0.05):
    q0, v0, _ = case.initial
    return cache.solution(case, "reference", (q0, v0), t_end, "DOP853", **OPTIONS)


def entries(folder):
    return sorted(folder.rglob("*.pkl"))


def no_simulation(*args, **kwargs):
    raise AssertionError("simulated, where the cache holds the solution")


def test_a_cached_solution_is_what_simulate_computes_bit_for_bit(folder, monkeypatch):
    case = dyncheck.load_case("rotating_pendulum")
    computed = solve(case)
    q0, v0, _ = case.initial
    pd.testing.assert_frame_equal(computed, simulate(case.model("reference"), (q0, v0), 0.05, "DOP853", **OPTIONS),
                                  check_exact=True)
    assert len(entries(folder)) == 1
    monkeypatch.setattr(cache, "simulate", no_simulation)
    again = solve(case)
    pd.testing.assert_frame_equal(again, computed, check_exact=True)
    assert again.attrs == computed.attrs


@pytest.mark.parametrize("change", ["parameter", "span", "case file", "code", "kernels"])
def test_anything_the_solution_depends_on_makes_a_new_key(folder, monkeypatch, tmp_path, change):
    own = tmp_path / "cases"
    shutil.copytree(CASES / "rotating_pendulum", own / "rotating_pendulum")
    case = dyncheck.load_case("rotating_pendulum", own)
    solve(case)
    if change == "parameter":
        case = dyncheck.load_case("rotating_pendulum", own, g=9.80665)
    elif change == "case file":  # a comment only: the case file is hashed whole
        file = own / "rotating_pendulum" / "case.toml"
        file.write_text(file.read_text() + "\n# edited\n")
    elif change == "code":
        monkeypatch.setattr(cache, "code_version", lambda: "another version")
    elif change == "kernels":  # as a run with OPENBLAS_CORETYPE set, or on another processor, has them
        kernels = cache.kernels()
        monkeypatch.setattr(cache, "kernels", lambda: (kernels[0], "Haswell" if kernels[1] != "Haswell" else None))
        cache.code_version.cache_clear()  # memoised: the kernels are fixed once numpy has loaded
    solve(case, 0.06 if change == "span" else 0.05)
    if change == "kernels":
        cache.code_version.cache_clear()  # not to keep the patched kernels' version
    assert len(entries(folder)) == 2


def test_a_module_imported_from_outside_the_checkout_is_in_the_key(folder, monkeypatch, tmp_path):
    """A case may name its derivation by module, from anywhere on the path, and a derivation may import a
    researcher's own library: an edit of either is a new key, as an edit of the case folder is."""
    library = tmp_path / "library"
    library.mkdir()
    (library / "researchers_terms.py").write_text("TERM = 1.0\n")
    monkeypatch.syspath_prepend(str(library))
    monkeypatch.delitem(sys.modules, "researchers_terms", raising=False)
    importlib.import_module("researchers_terms")
    case = dyncheck.load_case("rotating_pendulum")
    solve(case)
    solve(case)
    assert len(entries(folder)) == 1
    (library / "researchers_terms.py").write_text("TERM = 2.0  # edited\n")
    solve(case)
    assert len(entries(folder)) == 2


def test_without_the_cache_nothing_is_read_or_written(folder, monkeypatch):
    case = dyncheck.load_case("rotating_pendulum")
    solve(case)
    monkeypatch.setattr(cache, "enabled", False)
    calls = []
    monkeypatch.setattr(cache, "simulate", lambda *a, **k: calls.append(a) or simulate(*a, **k))
    solve(case)
    solve(case, 0.06)
    assert len(calls) == 2 and len(entries(folder)) == 1


def test_a_torn_entry_is_computed_again(folder):
    case = dyncheck.load_case("rotating_pendulum")
    computed = solve(case)
    entry, = entries(folder)
    entry.write_bytes(entry.read_bytes()[:100])
    pd.testing.assert_frame_equal(solve(case), computed, check_exact=True)


def test_old_code_versions_are_pruned(folder, monkeypatch):
    case = dyncheck.load_case("rotating_pendulum")
    for i in range(cache.KEPT_VERSIONS + 2):
        monkeypatch.setattr(cache, "code_version", lambda i=i: f"version-{i}")
        solve(case)
    assert len([p for p in folder.iterdir()]) == cache.KEPT_VERSIONS
