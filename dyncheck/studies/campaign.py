"""`dyncheck campaign`: a case's sources compared at many random parameter sets, and its stability maps, on Dask.

Each parameter set (drawn as `pointwise.parameter_sets` draws them) gets its own seeded random states; at each the
pointwise checks run as `dyncheck run` runs them (`pointwise.pointwise`, the book's printed rows, the program's
formulas, the findings' right sides), and `checks.apply_findings` marks the rows each registered finding explains,
so a finding's size at a set is the largest error of its rows there.  The sets go to the workers in chunks; each
finished chunk is one Parquet file named by its index and a key of everything it depends on (the case folder, the
code, the overrides, its sets, the states per set), so a campaign restarted with the same arguments computes only
the chunks it lacks, and a changed case or code computes them all again (docs/campaign.md)."""

import hashlib
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from dyncheck.case.folder import Case, load_case
from dyncheck.checks import pointwise, programs
from dyncheck.checks import runs as checks, residuals
from dyncheck.results.values import Status
from dyncheck.run.cache import case_version, code_version
from dyncheck.studies import stability

# The columns of a chunk's table besides the case's parameters (one per parameter, its value at the set) and the
# state where a comparison of two sources differs most (state_t, state_<coordinate>, state_<coordinate>_rate).
COLUMNS = ("set", "check", "comparison", "quantity", "error", "tolerance", "status", "finding", "reason", "state",
           "seconds")


@dataclass(frozen=True)
class Chunk:
    """A task: the sets `first`, `first` + 1, ... of a campaign, each with `states` random states."""
    case: str
    cases_dir: str
    overrides: tuple  # ((name, value), ...)
    index: int
    first: int
    sets: tuple  # ({name: value}, ...), the random values of each set
    states: int
    key: str

    @property
    def file(self):
        return f"chunk-{self.index:05d}-{self.key}.parquet"


@dataclass(frozen=True)
class Plan:
    """A campaign: its chunks, the sets that could not be drawn, and where its files go."""
    case: Case
    chunks: tuple
    missing: int
    out: Path

    @property
    def folder(self):
        return self.out / "chunks"

    def todo(self):
        """The chunks without their file: those a restart computes."""
        return [chunk for chunk in self.chunks if not (self.folder / chunk.file).is_file()]


def plan(case, sets, states, chunk, out):
    """The campaign's chunks: `sets` parameter sets of `case` (its overrides fixed), `chunk` sets per task."""
    drawn, missing = pointwise.parameter_sets(case, sets)
    clash = set(case.params) & (set(COLUMNS) | {c for c in case.params if c.startswith("state_")})
    if clash:
        raise ValueError(f"{case.origin}: parameter {sorted(clash)[0]!r} has the name of a campaign column; "
                         f"the campaign's own columns are {', '.join(COLUMNS)}, state_*")
    fixed = (code_version(), case_version(case), sorted(case.overrides.items()), states)
    chunks = []
    for index, first in enumerate(range(0, len(drawn), chunk)):
        part = tuple(drawn[first:first + chunk])
        key = hashlib.sha256(json.dumps([fixed, first, part]).encode()).hexdigest()[:16]
        chunks.append(Chunk(case.name, str(case.folder.parent), tuple(sorted(case.overrides.items())), index, first,
                            part, states, key))
    return Plan(case, tuple(chunks), missing, Path(out))


def at_set(case, params, states, index):
    """The case at a parameter set, with `states` random states of its own (seeded by the case's seed and the
    set's index)."""
    seed = int(np.random.SeedSequence([case.spec["sample"]["params"]["seed"], index]).generate_state(1)[0])
    spec = {**case.spec, "sample": {**case.spec["sample"], "count": states, "seed": seed}}
    return Case(case.folder, {**case.overrides, **params}, spec, case.derivation)


def measure_set(case, params, states, index):
    """The rows of the pointwise checks at one parameter set, the findings' rows marked, and the sample."""
    at = at_set(case, params, states, index)
    rows, sample = pointwise.pointwise(at)
    rows += residuals.printed_rows(at, sample)
    rows += programs.program_pointwise(at, sample) if at.has_program else []
    rows = checks.apply_findings(at, rows) + programs.right_sides(at, sample)[0]
    return (checks.in_own_words(rows) if at.one_derivation else rows), sample, at


def tidy(rows, sample, at, index, seconds):
    """One record per row: the row, the set's parameters, and for two sources' comparison the state where they
    differ most."""
    records = []
    for r in rows:
        record = {"set": index, "check": r.check, "comparison": r.comparison, "quantity": r.quantity,
                  "error": math.nan if r.error is None else r.error,
                  "tolerance": math.nan if r.tolerance is None else r.tolerance, "status": str(r.status),
                  "finding": r.finding or "", "reason": r.detail if r.error is None else "", "state": -1,
                  "seconds": seconds, **at.params}
        values = sample["values"] if sample else {}
        if r.check == "pointwise" and len(r.sources) == 2 and all(r.quantity in values.get(s, {}) for s in r.sources):
            a, b = (values[s][r.quantity] for s in r.sources)
            i = int(np.argmax(np.abs(a - b)))
            t, q, v = sample["states"][i]
            record.update({"state": i, "state_t": t, **{f"state_{c}": x for c, x in zip(at.coords, q)},
                           **{f"state_{c}_rate": x for c, x in zip(at.coords, v)}})
        records.append(record)
    return records


def run_chunk(chunk):
    """A chunk's table (a worker's task): a set that fails is a row saying why, never an exception."""
    case = load_case(chunk.case, Path(chunk.cases_dir), **dict(chunk.overrides))
    records = []
    for offset, params in enumerate(chunk.sets):
        index = chunk.first + offset
        start = time.perf_counter()
        try:
            rows, sample, at = measure_set(case, params, chunk.states, index)
        except Exception as error:  # any failure of a source at this set (loading its scene, its arithmetic)
            failed = {"set": index, "check": "campaign", "comparison": "every source", "quantity": "every quantity",
                      "error": math.nan, "tolerance": math.nan, "status": str(Status.FAIL), "finding": "",
                      "reason": f"{type(error).__name__}: {' '.join(str(error).split())}", "state": -1,
                      "seconds": time.perf_counter() - start, **case.params, **params}
            records.append(failed)
            continue
        records += tidy(rows, sample, at, index, time.perf_counter() - start)
    return pd.DataFrame.from_records(records)


def write_parquet(table, path):
    """Whole or not at all: written beside `path`, then renamed over it (a killed campaign leaves no half file)."""
    partial = path.with_name(f".{path.name}.tmp")
    table.to_parquet(partial, index=False)
    partial.replace(path)


def run(plan, client, progress=None):
    """Compute the plan's missing chunks on the Dask `client`, writing each as it finishes; returns the seconds."""
    from dask.distributed import as_completed
    start = time.perf_counter()
    plan.folder.mkdir(parents=True, exist_ok=True)
    futures = [client.submit(run_chunk, chunk, key=f"campaign-{chunk.case}-{chunk.key}", pure=False)
               for chunk in plan.todo()]
    by_future = dict(zip(futures, plan.todo()))
    for future in as_completed(futures):
        write_parquet(future.result(), plan.folder / by_future[future].file)
        if progress:
            progress()
    return time.perf_counter() - start


def results(plan):
    """The plan's chunks read back, one table (chunks of other keys in the folder are left out)."""
    tables = [pd.read_parquet(plan.folder / chunk.file) for chunk in plan.chunks]
    return pd.concat(tables, ignore_index=True) if tables else pd.DataFrame(columns=COLUMNS)


# -- the stability maps ------------------------------------------------------------------------------------------

def maps(case):
    """The case's maps (its study module's MAPS): {name: stability.common.Map}."""
    module = stability.case_module(case)
    return dict(getattr(module, "MAPS", {})) if module else {}


def map_cell(case_name, cases_dir, overrides, name, x, y):
    """One cell of a map (a worker's task)."""
    case = load_case(case_name, Path(cases_dir), **dict(overrides))
    return {"x": x, "y": y, **maps(case)[name].cell(case, x, y)}


def run_maps(case, client, n, out, progress=None):
    """Each map of the case on an n x n grid, its cells as Dask tasks; {name: table}, each saved as Parquet under a
    key of the case, the code and the grid (a map already computed is read back)."""
    from dask.distributed import as_completed
    tables = {}
    for name, spec in maps(case).items():
        xlabel, xs, ylabel, ys = spec.grid(case, n)
        key = hashlib.sha256(json.dumps([code_version(), case_version(case), sorted(case.overrides.items()),
                                         list(map(float, xs)), list(map(float, ys))]).encode()).hexdigest()[:16]
        path = Path(out) / "maps" / f"{name}-{n}-{key}.parquet"
        if not path.is_file():
            path.parent.mkdir(parents=True, exist_ok=True)
            overrides = tuple(sorted(case.overrides.items()))
            futures = [client.submit(map_cell, case.name, str(case.folder.parent), overrides, name, float(x), float(y),
                                     pure=False) for x in xs for y in ys]
            cells = []
            for future in as_completed(futures):
                cells.append(future.result())
                if progress:
                    progress()
            write_parquet(pd.DataFrame(cells).sort_values(["x", "y"], ignore_index=True), path)
        tables[name] = (spec, xlabel, ylabel, pd.read_parquet(path))
    return tables


# -- the command -------------------------------------------------------------------------------------------------

CONNECT_TIMEOUT = "10s"  # how long to try an existing cluster's scheduler


def connect(workers, scheduler):
    """A Dask client: of the cluster at `scheduler`, or of a LocalCluster of `workers` single-threaded processes (the
    engines and the Python derivations hold the GIL).  ValueError when the scheduler cannot be reached."""
    from dask.distributed import Client, LocalCluster
    if scheduler:
        try:
            return Client(scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError, ValueError) as error:
            raise ValueError(f"--scheduler {scheduler}: cannot reach it: {' '.join(str(error).split())}") from None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0")
    return Client(cluster)


def command(case, plan, grid, workers, scheduler):
    """Run the plan's missing chunks and the case's maps: (the whole table, the maps drawn, the wall time, the
    workers, the sets computed now), for the page (dyncheck.pages.campaign_page.write)."""
    from dyncheck.common.progress import Progress
    todo = plan.todo()
    client = connect(workers, scheduler)
    try:
        workers = len(client.scheduler_info()["workers"]) or workers
        with Progress(f"campaign {case.name}", total=len(plan.chunks), initial=len(plan.chunks) - len(todo),
                      unit="chunk") as bar:
            wall = run(plan, client, bar.step)
        drawn = {}
        if grid and maps(case):
            with Progress(f"maps of {case.name}", total=grid * grid * len(maps(case)), unit="cell") as bar:
                drawn = run_maps(case, client, grid, plan.out, bar.step)
    finally:
        client.close()
        if client.cluster is not None:
            client.cluster.close()
    return results(plan), drawn, wall, workers, sum(len(c.sets) for c in todo)
