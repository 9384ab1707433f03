"""Markdown reports with figures: reports/<case>.md per case, reports/index.md and errata.md, rendered
from results alone (dyncheck.results.values.CaseResult): no engine is imported here, nothing is computed
but what the pages show.  The results are saved in the report's results/ folder, and the pages are
rendered from what was saved, so that `dyncheck report --from reports/results` renders them again.

The new report is built whole in a folder beside the old one and swapped in with one atomic
rename, so a failed, interrupted or killed run leaves the previous report intact.
"""

import ctypes
import errno
import fcntl
import json
import math
import os
import re
import shutil
import sys
from contextlib import closing, contextmanager
from pathlib import Path

import pandas as pd

from dyncheck.case import isolation
from dyncheck.case.folder import Case
from dyncheck.common.messages import plural, statuses_in_words
from dyncheck.common.style import embed
from dyncheck.pages import student_page, typeset, vibration_page
from dyncheck.pages.case_page import (CPU_TIES, CPU_TIME, SUMMARY_KEYS, markdown_table, random_tried, size,
                                      sweep_in_words, worst_engine_error, write_case_page, write_unfinished_page)
from dyncheck.results.values import RESULTS_VERSION, case_json, load_result, save_results
from dyncheck.studies import work_precision


def write_reports(results, out, animations=True, case_written=lambda name: None):
    """Write the pages of `results` into the folder `out`, keeping what it holds of other cases, and
    return the files written (relative to `out`); `animations`: with each case's GIF; `case_written(name)`
    is told as each case's pages are done (a case's pages and GIF take tens of seconds: the progress).

    The new tree is a copy of `out` with this run's files written over it, and its index and errata
    are made from the summaries it holds; it is built beside `out` and exchanged with it in one
    rename, so a reader sees the previous report or the new one, never a mix.  Writers into one
    folder take turns (`locked`), each building on the last one's report."""
    out = Path(out).resolve()  # through a symbolic link: the link stays, the folder it names is replaced
    with locked(out):
        remove_stale_trees(out)
        tree = out.parent / f"{temp_prefix(out)}{os.getpid()}"
        try:
            tree.mkdir()
            if out.is_dir():  # `.tmp-*`: what killed runs of earlier versions left inside `out`
                shutil.copytree(out, tree, dirs_exist_ok=True, ignore=shutil.ignore_patterns(".tmp-*"))
            (tree / "figures").mkdir(exist_ok=True)
            (tree / "data").mkdir(exist_ok=True)
            save_results(results, tree / "results")
            written = [f"results/{result.name}" for result in results]
            # A case's figures and GIF take tens of seconds: the cases' pages are written at once, one per core, each
            # in a forked process of its own (files of its own names; the index and errata below read them all).
            workers = min(len(results), os.cpu_count() or 1) or 1
            pages = isolation.each_forked([result.name for result in results],
                                          lambda name: case_pages(tree / "results" / name, tree, animations), workers,
                                          lambda name: isolation.Budget(math.inf, math.inf,
                                                                        isolation.machine_memory() // workers))
            with closing(pages):
                for index, (kind, value) in pages:
                    if kind == "interrupted":
                        raise KeyboardInterrupt
                    if kind != "result":
                        raise RuntimeError(f"the pages of {results[index].name} were not written: {value}")
                    written += value
                    case_written(results[index].name)
            cases = summaries(tree, out)
            written.append(write_index(tree, cases))
            written += write_index_timing(tree, cases)
            if not all(c["one_derivation"] for c in cases):  # the book's errata; a researcher's case has no book
                written.append(write_errata(tree, cases))
            swap(tree, out)
        finally:  # this run's tree after a failure, or the previous report after the swap
            if tree.exists():
                shutil.rmtree(tree)
    return written


def temp_prefix(out):
    return f".{out.name}.tmp-"


@contextmanager
def locked(out):
    """Hold the lock on `out` (flock on a file beside it, released by the system if we are killed).
    A second writer waits its turn rather than fail: the first one's wait is seconds, and both
    reports then land, the second built on the first."""
    with open(out.parent / f".{out.name}.lock", "a+") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            lock.seek(0)
            print(f"dyncheck: waiting for {lock.read().strip() or 'another writer'}, which is writing {out}",
                  file=sys.stderr)
            fcntl.flock(lock, fcntl.LOCK_EX)
        lock.truncate(0)
        lock.write(f"dyncheck pid {os.getpid()}\n")
        lock.flush()
        yield


def remove_stale_trees(out):
    """Trees beside `out` that killed writers left; only called under the lock, so no live writer has
    one.  A writer killed between the two renames of `swap` left the previous report aside: put back."""
    for path in sorted(out.parent.iterdir()):
        if path.name.startswith(temp_prefix(out)):
            if path.name.endswith(PREVIOUS) and not out.exists():
                path.rename(out)
            else:
                shutil.rmtree(path)


PREVIOUS = "-previous"  # the name's end of the previous report while `swap` cannot exchange
RENAME_EXCHANGE = 2  # <linux/fs.h>
AT_FDCWD = -100  # <fcntl.h>: paths relative to the working directory


def swap(new, out):
    """Put the tree `new` at `out` and the previous one, if any, at `new`."""
    if not out.exists():
        os.rename(new, out)
    elif not exchange(new, out):
        # No atomic exchange here (not Linux, or a file system without it): `out` is missing for a
        # moment between the two renames, but it is never a mix of two reports.
        previous = new.with_name(new.name + PREVIOUS)
        os.rename(out, previous)
        os.rename(new, out)
        os.rename(previous, new)


def exchange(a, b):
    """Exchange two paths in one atomic step (Linux's renameat2 with RENAME_EXCHANGE, which
    Python's os does not offer); False where the system cannot."""
    renameat2 = getattr(ctypes.CDLL(None, use_errno=True), "renameat2", None)
    if renameat2 is None:
        return False
    if renameat2(AT_FDCWD, os.fsencode(a), AT_FDCWD, os.fsencode(b), RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS):  # the file system or kernel lacks it
        return False
    raise OSError(code, os.strerror(code), os.fsdecode(b))


def write_summary(result, case, tmp):
    """data/<case>.json: the case's results (the schema of `dyncheck run --json`) for the index."""
    rows = result.rows
    sweep = sweep_in_words(result.studies["work_precision"], case) if result.studies else None
    worst = worst_engine_error(rows)
    summary = {"version": RESULTS_VERSION, **case_json(result), "title": case.title,
               "overridden": case.overrides_text(),  # in words, for the index and errata
               "one_derivation": case.one_derivation,  # the index's words: a researcher's or the book's
               "worst_engine_error": worst if math.isfinite(worst) else None,  # JSON has no NaN
               "random": random_tried(result, case),
               "cheapest": None if sweep is None or sweep.empty else  # for the index: level -> method
               {f"{r['level']:.0e}": r["cheapest"] for _, r in work_precision.cheapest(sweep).iterrows()},
               "vibration": vibration_page.summary(result.vibration),
               "typeset": [{"finding": f.id, **typeset_pair(pair)} for f in result.findings for pair in f.pairs]}
    rel = f"data/{case.name}.json"
    (tmp / rel).write_text(json.dumps(summary, indent=1) + "\n")
    return rel


def summaries(tree, out):
    """The summary of every case in `tree`'s data/, in book order.  A file there that write_summary
    did not write (foreign, broken, of another version) is skipped with a warning naming it in `out`."""
    cases = []
    for path in sorted((tree / "data").glob("*.json")):
        try:
            summary = json.loads(path.read_text())
        except (ValueError, RecursionError):  # not JSON, not UTF-8, or nested too deeply
            summary = None
        if isinstance(summary, dict) and SUMMARY_KEYS <= summary.keys() and summary["case"] == path.stem:
            cases.append(summary)
        else:
            print(f"dyncheck: warning: {out / 'data' / path.name} is not a case summary that dyncheck report"
                  " wrote; left out of the index", file=sys.stderr)
    return sorted(cases, key=lambda c: section_key(str(c["section"])))


def section_key(section):
    """Book order for any section string: numbers as numbers ("1.9" before "1.10"), the rest as
    text ("1.7" before "1.7a", all of them before "new")."""
    parts = re.split(r"([0-9]+)", section)  # the numbers at the odd places
    return [(0, int(part)) if i % 2 else (1, part) for i, part in enumerate(parts)]


def with_overrides(summary):
    """", with k = 500 N/m (book: 2000)" for a case run with overrides, else nothing."""
    return f", with {summary['overridden']}" if summary.get("overridden") else ""


def typeset_pair(pair):
    """A finding's Pair as the errata show it: both sides in LaTeX, what differs boxed, and their origins."""
    printed, right = typeset.marked(pair.printed, pair.right, pair.symbols)
    lhs = typeset.latex(pair.lhs, pair.symbols) + " = " if pair.lhs else ""
    return {"printed": lhs + printed, "right": lhs + right, "printed_from": pair.printed_from,
            "right_from": pair.right_from}


def errata_pairs(pairs):
    """The lines of a finding's typeset pairs: "As printed" and "Right", each a display formula."""
    lines = []
    for pair in pairs:
        lines += [f"*As printed* ({pair['printed_from']}):", "", "$$", pair["printed"], "$$", "",
                  f"*Right* ({pair['right_from']}):", "", "$$", pair["right"], "$$", ""]
    return lines


def write_errata(tmp, cases):
    """errata.md: every finding of every case in one table, then each in full."""
    table = [{"finding": f"[{f['id']}](#{f['id'].replace('.', '').lower()})",
              "case": f"[{c['case']}]({c['case']}.md)" + with_overrides(c),
              "where": f["where"], "what": f["title"], "largest relative error": size(f["error"]),
              "localised edit": f["localised"]}
             for c in cases for f in c["findings"]]
    lines = ["# Errata: where the book is wrong", "",
             "Each finding is a disagreement between the book and the engines that an error of the book"
             " explains.  It is registered in its case file and checked on every run: if the book's"
             " version ever agrees with the engines, the run fails.  [All cases](index.md)", "",
             markdown_table(pd.DataFrame(table)) if table else "No findings.", ""]
    for c in cases:
        for f in c["findings"]:
            lines += [f"## {f['id']}", "",
                      f"**{f['title']}** ([{c['case']}]({c['case']}.md), {c['section']}{with_overrides(c)})", "",
                      f"- *Where:* {f['where']}",
                      f"- *Quantities:* {', '.join(f['quantity'])}; largest relative error {size(f['error'])}",
                      f"- *How established:* {f['established']}",
                      *([f"- *Effect:* {f['effect']}"] if f["effect"] else []),
                      *([f"- *Measured in this run:* {f['measured']}"] if f.get("measured") else []),
                      f"- *Localised edit:* {f['localised']}", "",
                      *errata_pairs([pair for pair in c.get("typeset", []) if pair["finding"] == f["id"]]),
                      f["explanation"], ""]
    programs = [c for c in cases if (tmp / f"figures/{c['case']}_program.png").exists()]
    if programs:
        lines += ["## The book's programs: its figures redrawn", "",
                  "Each figure the book draws from a program, from a line-by-line transcription of that"
                  " program (left) and from the reference's equations integrated tightly (right), on the"
                  " book's axes.", ""]
        for c in programs:
            lines += [f"### {c['section']} ([{c['case']}]({c['case']}.md))", "",
                      *embed(f"figures/{c['case']}_program.png", "program",
                             f"The book's figures of {c['section']} redrawn from its program (left, red dashed) and from"
                             " the reference's equations integrated tightly (right, black), each panel titled as the"
                             " book's; the dashed grey frame is the book's printed axes. The case page says when the"
                             " program leaves that motion.")]
    (tmp / "errata.md").write_text("\n".join(lines))
    return "errata.md"


def speed_table(tmp, cases):
    """Index lines: for each case with a work-precision sweep, the cheapest method at each accuracy, and in
    short which methods are cheapest (in CPU time: index_timing.md)."""
    rows = [{"case": f"[{c['case']}]({c['case']}.md#speed-against-accuracy)", **c["cheapest"]}
            for c in cases if c.get("cheapest")]
    if not rows:
        return []
    return ["The cheapest method (fewest right-hand-side evaluations) that reaches each relative trajectory error, from each"
            " case's work-precision sweep (details, charts and the stability studies on the case pages):", "",
            markdown_table(pd.DataFrame(rows).fillna("-")), "",
            f"In short, {work_precision.in_short(sweeps(tmp, cases))}.  In CPU time, which differs from run to run:"
            f" [{INDEX_TIMING}]({INDEX_TIMING}).", ""]


INDEX_TIMING = "index_timing.md"


def sweeps(tmp, cases, timing=False):
    """{case: its work-precision sweep as data/ holds it} for the cases with one (and their CPU times: timing).
    A timing file without every CPU-time column (an earlier version's) is left out with a warning naming it."""
    def csv(case, suffix):
        return tmp / "data" / f"{case}_work_precision{suffix}.csv"
    out = {}
    for case in (c["case"] for c in cases if c.get("cheapest")):
        frame = work_precision.read_csv(csv(case, ""), csv(case, "_timing") if timing else None)
        if timing and not set(work_precision.TIMING_COLUMNS) <= set(frame.columns):
            print(f"dyncheck: warning: data/{csv(case, '_timing').name} lacks CPU-time columns"
                  f" ({', '.join(sorted(set(work_precision.TIMING_COLUMNS) - set(frame.columns)))}; an earlier"
                  f" version's): left out of {INDEX_TIMING}", file=sys.stderr)
            continue
        out[case] = frame
    return out


def write_index_timing(tmp, cases):
    """index_timing.md: the index's speed table and sentence in CPU time, apart from the index because CPU
    times differ from run to run; [] and none (an earlier one removed) when no case has a sweep."""
    timed = sweeps(tmp, cases, timing=True)
    if not timed:
        (tmp / INDEX_TIMING).unlink(missing_ok=True)
        return []
    rows = [{"case": f"[{case}]({case}_timing.md)",
             **{f"{r['level']:.0e}": r["cheapest"] for _, r in work_precision.cheapest(frame, cost="cpu").iterrows()}}
            for case, frame in timed.items()]
    lines = ["# dyncheck reports: times", "",
             "Times of the last report on this machine, which differ from run to run; [the index](index.md).", "",
             "The cheapest method in CPU time that reaches each relative trajectory error, from each case's"
             " work-precision sweep (its timing page has the times).  " + CPU_TIME + "  " + CPU_TIES, "",
             markdown_table(pd.DataFrame(rows).fillna("-")), "",
             f"In short, {work_precision.in_short(timed, cost='cpu')}.", ""]
    (tmp / INDEX_TIMING).write_text("\n".join(lines))
    return [INDEX_TIMING]


def case_pages(saved, tree, animations):
    """The pages of the case whose results are saved in the folder `saved` (what `report --from` renders from),
    written into `tree`; the files written."""
    result = load_result(saved)
    case = Case(result.folder, result.overrides, result.spec)
    if not result.runs:  # its checks did not finish (dyncheck.checks.runs.unfinished)
        return [write_unfinished_page(result, case, tree), write_summary(result, case, tree)]
    return [*write_case_page(result, case, tree, animations),
            *student_page.write(result, case, tree),  # after the case page: it shows its figures
            write_summary(result, case, tree)]


def write_index(tmp, cases):
    """index.md over `cases` (the summaries)."""
    rows = []
    for case in cases:
        counts = pd.Series([c["status"] for c in case["checks"]]).value_counts()
        rows.append({
            "case": f"[{case['case']}]({case['case']}.md)" + (f" ([step by step]({case['case']}_student.md))" if
                                                                (tmp / f"{case['case']}_student.md").is_file() else ""),
            "section": case["section"],
            "title": case["title"] + with_overrides(case),
            "status": case["status"].upper(), "checks": statuses_in_words(counts),
            "worst engine error": "-" if case["worst_engine_error"] is None else f"{case['worst_engine_error']:.1e}",
            "findings": ", ".join(f"{f['id']} ({size(f['error'], '.2g')})" for f in case["findings"]) or "none"})
    compared = [c for c in cases if c["random"]["agreed"] is not None]
    tried = [c["random"] for c in compared]
    states = sum(t["states"] + t["parameter_sets"] * t["states_per_set"] for t in tried)
    disagreed = [c["case"] for c in compared if not c["random"]["agreed"]]
    not_compared = [c["case"] for c in cases if c["random"]["agreed"] is None]
    book = not any(c["one_derivation"] for c in cases)  # the book's examples, or (also) researchers' own cases
    derivations = "`reference`" if book else "the derivations"
    lines = ["# dyncheck reports", "",
             ("The worked examples of I. F. Santos, *Dynamics of Machines*, ch. 1, checked against MuJoCo"
              " and Pinocchio." if book else "Each case's derivation checked against MuJoCo and Pinocchio.")
             + f"  *Worst engine error* is the largest pointwise relative error among {derivations}, MuJoCo and"
             " Pinocchio (accelerations, reactions, energy, drive power)"
             + ("; a finding is an error of the book, with the largest relative error it causes: all of them"
                " are in the [errata](errata.md)." if any(c["findings"] for c in cases) else "."), "",
             markdown_table(pd.DataFrame(rows)), "",
             *speed_table(tmp, cases),
             *vibration_page.index_lines(cases, book),
             f"The last run tried {plural(sum(t['parameter_sets'] for t in tried), 'random parameter set')} besides"
             f" {'the book' if book else 'each case'}'s and {plural(states, 'random state')} in all"
             f" ({plural(len(compared), 'case')};"
             f" seeds on each case page): {derivations}, MuJoCo and Pinocchio "
             + (f"disagreed in {', '.join(disagreed)}." if disagreed else
                "agreed at every one of them within the pointwise tolerance.")
             + (f"  Not compared: {', '.join(not_compared)}, whose checks did not finish." if not_compared else ""),
             ""]
    (tmp / "index.md").write_text("\n".join(lines))
    return "index.md"
