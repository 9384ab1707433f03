"""Tight solutions kept across runs: a reference solution at rtol 1e-12 costs seconds and, with nothing
changed, comes out the same bit for bit, so a run takes it from here when one before it computed it.

An entry's key is a hash of everything the solution depends on: the sources of dyncheck, reference/ and
engines/, the versions of Python, numpy, scipy, pandas, MuJoCo and Pinocchio and the machine's
architecture (`code_version`); the sources of every other module imported from outside the Python
installation (`imported_code`: a derivation that a case names by module, or that imports a researcher's own
library, from anywhere on the path); every file of the case's folder and its parameters' values; and the
simulate call (source, initial state, span, method and options).  A change in any of them makes a new
key, so a stale entry is never read; it is deleted with its code version (KEPT_VERSIONS).

The folder: $DYNCHECK_CACHE, else $XDG_CACHE_HOME/dyncheck, else ~/.cache/dyncheck.  `--no-cache`
(`enabled = False`) computes everything and neither reads nor writes it.
"""

import functools
import hashlib
import os
import pickle
import platform
import sys
import sysconfig
import tempfile
from importlib.metadata import version
from pathlib import Path

import numpy as np

from dyncheck.run.simulate import simulate

enabled = True
KEPT_VERSIONS = 5  # code versions whose entries stay; older ones (other checkouts, earlier edits) go
CODE = ("dyncheck", "reference", "engines")  # the packages whose sources a result depends on
LIBRARIES = ("numpy", "scipy", "pandas", "mujoco", "pin")


def folder():
    root = os.environ.get("DYNCHECK_CACHE") or Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "dyncheck"
    return Path(root)


def _digest(paths, root, digest):
    """`digest` updated with the files' names (relative to `root`) and contents."""
    for path in sorted(paths):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return digest


@functools.cache
def code_version():
    """A hash of the code that computes a solution (the harness, the derivations, the engine adapters), of
    the libraries it runs on and of the kernels they run (`kernels`)."""
    root = Path(sys.modules["dyncheck"].__file__).parent.parent
    digest = _digest([p for package in CODE for p in (root / package).rglob("*.py")], root, hashlib.sha256())
    digest.update(repr((sys.version, platform.machine(), [version(name) for name in LIBRARIES], kernels())).encode())
    return digest.hexdigest()[:16]


def kernels():
    """What picks numpy's and OpenBLAS's loops, which round differently: the processor features numpy dispatches on
    (those NPY_DISABLE_CPU_FEATURES leaves on) and the kernel OpenBLAS is told to use (OPENBLAS_CORETYPE; else
    it picks by the same processor).  A solution made on AVX-512 kernels differs in its last digits from one made
    on AVX2 kernels: a cache folder shared by two machines, or a run with other settings, must not mix them."""
    try:
        from numpy._core._multiarray_umath import __cpu_features__ as features
    except ImportError:  # a numpy that keeps them elsewhere: the processor's name stands for them
        features = {platform.processor(): True}
    return sorted(name for name, enabled in features.items() if enabled), os.environ.get("OPENBLAS_CORETYPE")


def imported_code():
    """A hash of the sources of the modules imported from outside the Python installation (its standard library
    and site-packages) and CODE, read as the key is made: a case may name its derivation by module, and a
    derivation may import code of its own, from any folder on the path."""
    digest = hashlib.sha256()
    for path in sorted(filter(None, map(_outside, {getattr(m, "__file__", None) for m in list(sys.modules.values())}))):
        stat = os.stat(path)
        digest.update(path.encode() + b"\0" + _source_digest(path, stat.st_mtime_ns, stat.st_size) + b"\0")
    return digest.hexdigest()


@functools.cache
def _outside(file):
    """The real path of a module's source file when it lies outside the installation and CODE, else None."""
    if not file or not file.endswith(".py"):
        return None
    path = os.path.realpath(file)
    return None if path.startswith(_known_roots()) else path


@functools.cache
def _known_roots():
    root = Path(sys.modules["dyncheck"].__file__).parent.parent
    roots = [sysconfig.get_path(kind) for kind in ("stdlib", "platstdlib", "purelib", "platlib")]
    return tuple(os.path.join(os.path.realpath(r), "") for r in roots + [str(root / package) for package in CODE])


@functools.cache
def _source_digest(path, mtime_ns, size):
    """A file's hash, read again when it changes (its time or size: the arguments key the memo)."""
    with open(path, "rb") as file:
        return hashlib.sha256(file.read()).digest()


def case_version(case):
    """A hash of every file of the case's folder: case file, scenes, studies, a researcher's equations."""
    files = [p for p in case.folder.rglob("*") if p.is_file() and "__pycache__" not in p.parts]
    return _digest(files, case.folder, hashlib.sha256()).hexdigest()


def _exact(value):
    """`value` as text that tells every float apart (repr of an array rounds)."""
    if isinstance(value, np.ndarray):
        return [_exact(x) for x in value.tolist()]
    if isinstance(value, (tuple, list)):
        return [_exact(x) for x in value]
    if isinstance(value, float):
        return value.hex()
    return repr(value)


def solution(case, source, ic, t_end, method, **options):
    """simulate(case.model(source), ic, t_end, method, **options), from the cache when a run with the same
    key computed it.  A run that raises (Unstable) is not kept: it raises again, as computed."""
    if not enabled:
        return simulate(case.model(source), ic, t_end, method, **options)
    call = _exact((source, [np.asarray(x, dtype=float) for x in ic], float(t_end), method,
                   sorted((name, value) for name, value in options.items())))
    parameters = sorted((name, float(value).hex()) for name, value in case.params.items())
    key = hashlib.sha256(repr((case_version(case), imported_code(), parameters, call)).encode()).hexdigest()
    path = folder() / code_version() / f"{key}.pkl"
    try:
        with open(path, "rb") as file:
            return pickle.load(file)
    except (OSError, pickle.UnpicklingError, EOFError, AttributeError, ImportError):  # none yet, or a torn file
        pass
    run = simulate(case.model(source), ic, t_end, method, **options)
    _write(path, run)
    return run


def _write(path, run):
    """Write atomically (another process may be writing the same entry); a cache that cannot be written
    (a read-only home) only costs time."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        _prune(path.parent.parent, keep=path.parent.name)
        with tempfile.NamedTemporaryFile(dir=path.parent, delete=False, suffix=".tmp") as file:
            pickle.dump(run, file, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(file.name, path)
    except OSError:
        pass


def _prune(root, keep):
    """Delete the entries of all but the KEPT_VERSIONS most recently written code versions."""
    versions = sorted((p for p in root.iterdir() if p.is_dir() and p.name != keep),
                      key=lambda p: p.stat().st_mtime, reverse=True)
    for old in versions[KEPT_VERSIONS - 1:]:
        for entry in old.iterdir():
            entry.unlink(missing_ok=True)
        old.rmdir()
