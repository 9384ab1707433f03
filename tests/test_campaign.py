"""`dyncheck campaign`: random parameter sets on a Dask LocalCluster, resumable chunks, the page, the maps."""

import pandas as pd
import pytest

import dyncheck
from dyncheck import cli
from dyncheck.pages import campaign_page
from dyncheck.studies import campaign

CASE = "rotating_particle"  # the cheapest sets


@pytest.fixture(scope="module")
def client():
    """One single-worker LocalCluster for the module's campaigns (starting one takes seconds)."""
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=":0") as cluster:
        with distributed.Client(cluster) as c:
            yield c


@pytest.mark.full
def test_a_campaign_writes_chunks_that_read_back_resume_and_summarise(client, tmp_path):
    case = dyncheck.load_case(CASE)
    plan = campaign.plan(case, 20, 3, 5, tmp_path)
    assert len(plan.chunks) == 4 and len(plan.todo()) == 4
    campaign.run(plan, client)
    table = pd.read_parquet(plan.folder)
    assert sorted(table["set"].unique()) == list(range(20))
    assert {"error", "comparison", "quantity", "finding", *case.params} <= set(table.columns)
    # Resumable: only a chunk whose file is gone is computed again.
    written = {chunk.file: (plan.folder / chunk.file).stat().st_mtime_ns for chunk in plan.chunks}
    (plan.folder / plan.chunks[2].file).unlink()
    again = campaign.plan(case, 20, 3, 5, tmp_path)
    assert again.todo() == [again.chunks[2]]
    campaign.run(again, client)
    assert all((plan.folder / f).stat().st_mtime_ns == t for f, t in written.items() if f != plan.chunks[2].file)
    pd.testing.assert_frame_equal(campaign.results(again).drop(columns="seconds"), table.drop(columns="seconds"))
    # Whatever a chunk depends on changes its key: nothing stale is read.
    assert all(c.key != d.key for c, d in zip(plan.chunks, campaign.plan(case, 20, 4, 5, tmp_path).chunks))
    assert all(c.key != d.key for c, d in zip(plan.chunks, campaign.plan(case.with_params(g=5.0), 20, 3, 5,
                                                                           tmp_path).chunks))
    page, timing = campaign_page.write(case, again, campaign.results(again), {}, 1.0, 1, 5)
    text = page.read_text()
    agreeing = table[table["comparison"].isin(campaign_page.AGREEING)]
    assert "## Worst disagreement between sources" in text
    assert f"**{agreeing['error'].max():.3g}**" in text
    assert "sets/min/core" in timing.read_text() and "sets/min" not in text.replace(timing.name, "")
    # Deterministic: drawn again from the same results, the same bytes.
    assert campaign_page.write(case, again, campaign.results(again), {}, 2.0, 1, 5)[0].read_text() == text


def test_a_set_that_fails_is_a_row_saying_why(monkeypatch):
    case = dyncheck.load_case(CASE)
    chunk = campaign.plan(case, 3, 2, 3, "unused").chunks[0]
    real = campaign.measure_set

    def failing(case, params, states, index):
        if index == 1:
            raise ArithmeticError("overflow in the reference")
        return real(case, params, states, index)

    monkeypatch.setattr(campaign, "measure_set", failing)
    table = campaign.run_chunk(chunk)
    failed = table[table["set"] == 1]
    assert len(failed) == 1 and failed["status"].iloc[0] == "fail"
    assert "overflow in the reference" in failed["reason"].iloc[0]
    assert set(table["set"]) == {0, 1, 2}


@pytest.mark.parametrize("arguments, message", [
    (["nocase", "--sets", "3"], "unknown case 'nocase'"),
    ([CASE, "--sets", "0"], "--sets 0: must be at least 1"),
    ([CASE, "--sets", "many"], "--sets many: not a whole number"),
    ([CASE, "--sets", "3", "--states", "1.5"], "--states 1.5: not a whole number"),
])
def test_bad_input_is_one_line_and_exit_2(arguments, message, capsys, tmp_path):
    assert cli.main(["campaign", *arguments, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_an_unreachable_scheduler_is_one_line_and_exit_2(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(campaign, "CONNECT_TIMEOUT", "1s")
    assert cli.main(["campaign", CASE, "--sets", "2", "--scheduler", "tcp://127.0.0.1:1", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "--scheduler tcp://127.0.0.1:1: cannot reach it" in err and len(err.splitlines()) == 1


@pytest.mark.full
def test_the_stability_map_runs_as_tasks_and_is_drawn(client, tmp_path):
    case = dyncheck.load_case("spring_pendulum")
    drawn = campaign.run_maps(case, client, 2, tmp_path)
    spec, xlabel, ylabel, cells = drawn["stable_step"]
    assert len(cells) == 4 and set(cells.columns) >= {"x", "y", "value", "theory", "status"}
    assert (cells["value"].notna() | (cells["status"] != "measured")).all()
    lines = campaign_page.page(case, campaign.plan(case, 1, 1, 1, tmp_path), pd.DataFrame(
        columns=list(campaign.COLUMNS)), drawn, tmp_path)
    assert (tmp_path / "campaign_spring_pendulum_stable_step.png").is_file()
    assert any(line.startswith("*Figure: ") for line in lines)


@pytest.mark.slow
def test_ten_thousand_sets(tmp_path):
    assert cli.main(["campaign", CASE, "--sets", "10000", "--states", "3", "--grid", "0", "--out", str(tmp_path)]) == 0
    assert pd.read_parquet(tmp_path / "chunks")["set"].nunique() == 10000
