"""A report made again with nothing changed is the same, file for file, apart from the files named for
their timings: times, which differ from run to run, go only there (issue 12)."""

from dataclasses import replace

import pandas as pd

from dyncheck.pages.report import write_reports
from dyncheck.results.values import Outcome
from dyncheck.studies import work_precision


def small_sweep(case):
    """A work-precision sweep of a few points (the real one takes a minute)."""
    case.spec["work_precision"].update(t_end=0.3, output_step=0.01, repeat=2,
                                       solution={"rtol": 1e-11, "max_step": 0.01},
                                       sweep={"reference": {"DOP853": [1e-5, 1e-8]}, "mujoco": {"mujoco:RK4": [1e-3]}})
    return work_precision.sweep(case)


def slower(result, factor):
    """The same result with every time multiplied by `factor`: what another run would measure."""
    def timed(frame):
        if frame is None:
            return None
        frame = frame.copy()
        frame.attrs = {**frame.attrs, "wall": frame.attrs["wall"] * factor, "cpu": frame.attrs["cpu"] * factor}
        return frame
    runs = {source: replace(outcome, run=timed(outcome.run), twin=timed(outcome.twin)) if outcome.ok else outcome
            for source, outcome in result.runs.items()}
    sweep = result.studies["work_precision"].copy()
    sweep[[c for c in work_precision.TIMING_COLUMNS if c != "repeats"]] *= factor
    assert all(isinstance(outcome, Outcome) for outcome in runs.values())
    return replace(result, runs=runs, wall=result.wall * factor, studies={**result.studies, "work_precision": sweep})


def files(folder):
    return {path.relative_to(folder).as_posix(): path.read_bytes() for path in folder.rglob("*")
            if path.is_file() and "results" not in path.parts}


def test_only_the_timing_files_change_when_only_times_do(results, tmp_path):
    import dyncheck
    case = dyncheck.load_case("spring_pendulum")  # with a program figure, findings and a sweep
    result = results["spring_pendulum"].with_studies({"work_precision": small_sweep(case), "stability": []})
    write_reports([result], tmp_path / "a")
    write_reports([slower(result, 3.0)], tmp_path / "b")
    a, b = files(tmp_path / "a"), files(tmp_path / "b")
    assert a.keys() == b.keys()
    changed = {name for name in a if a[name] != b[name]}
    assert changed and all("timing" in name for name in changed), changed
    timing = {name for name in a if "timing" in name}
    assert timing == {"spring_pendulum_timing.md", "index_timing.md", "data/spring_pendulum_work_precision_timing.csv",
                      "figures/spring_pendulum_work_precision_timing.png",
                      "figures/spring_pendulum_work_precision_timing.pdf"}
    page = (tmp_path / "a" / "spring_pendulum.md").read_text()
    assert "wall time [s]" not in page and "CPU [s]" not in page and " took " not in page
    assert "(spring_pendulum_timing.md)" in page
    csv = pd.read_csv(tmp_path / "a" / "data" / "spring_pendulum_work_precision.csv", comment="#")
    assert not set(work_precision.TIMING_COLUMNS) & set(csv.columns)
    timing_csv = pd.read_csv(tmp_path / "a" / "data" / "spring_pendulum_work_precision_timing.csv", comment="#")
    assert (timing_csv["cpu_min"] <= timing_csv["cpu"]).all() and (timing_csv["cpu"] <= timing_csv["cpu_max"]).all()
    assert set(timing_csv["repeats"]) <= {2, work_precision.DECIDING_REPEATS}  # `repeat`, or deciding the CPU-time table
