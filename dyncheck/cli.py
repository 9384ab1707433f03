"""Command line: `dyncheck list | run | report`.  Exit codes: 0 all pass, 1 a check failed, 2 bad input,
130 interrupted (Ctrl-C)."""

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import mujoco
import pandas as pd
from tqdm import tqdm

from dyncheck import stability, work_precision
from dyncheck.case import SOURCES, case_names, load_case
from dyncheck.checks import findings_of, run_case
from dyncheck.schema import suggest

OK_STATUSES = ("pass", "finding")
TABLE_COLUMNS = ["check", "quantity", "sources", "error", "tolerance", "status"]


def main(argv=None):
    parser = argparse.ArgumentParser(prog="dyncheck", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    commands.add_parser("list", help="list the cases")
    run = commands.add_parser("run", help="run the checks and print a table")
    report = commands.add_parser("report", help="run the checks and write Markdown reports with figures")
    bench = commands.add_parser("bench", help="throughput of each source and the harness's overhead")
    bench.add_argument("cases", nargs="*", metavar="CASE", help="cases to measure (default: all)")
    bench.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help=argparse.SUPPRESS)
    for sub in (run, report):
        sub.add_argument("cases", nargs="*", metavar="CASE", help="cases to run (default: all)")
        sub.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                         help="override a parameter in every selected case that has it")
    run.add_argument("--json", type=Path, metavar="PATH", help="also write the results as JSON")
    report.add_argument("--out", type=Path, default=Path("reports"), metavar="DIR",
                        help="where to write the reports (default: reports)")
    report.add_argument("--no-studies", action="store_true",
                        help="leave out the work-precision and stability studies (minutes) from the pages")
    args = parser.parse_args(argv)
    # MuJoCo prints a line for each run that blows up, and the studies blow runs up on purpose: each
    # is reported instead as an unstable row, from the warnings MuJoCo counts in its data.
    mujoco.set_mju_user_warning(lambda message: None)
    try:
        if args.command == "list":
            return list_cases()
        cases = select_cases(args.cases, args.set)
        if args.command == "run" and args.json:
            check_json_path(args.json)
        if args.command == "report":
            check_out_folder(args.out)
    except ValueError as error:
        return error_exit(error)
    if args.command == "bench":
        from dyncheck.bench import bench_case
        table = pd.concat([bench_case(case) for case in cases], ignore_index=True)
        table["ratio to bare"] = table["ratio to bare"].map(lambda x: "-" if pd.isna(x) else f"{x:.3g}")  # no bare loop
        print(table.to_string(index=False, float_format=lambda x: f"{x:.3g}"))
        return 0
    try:
        results, interrupted = run_cases(cases)
        if args.command == "run":
            print_results(results)
            if args.json:
                marked = {"incomplete": f"interrupted (Ctrl-C) during case {interrupted}"} if interrupted else {}
                write_json({**to_json(results), **marked}, args.json)
        elif not interrupted:  # a report of some cases would pass for one of all
            make_report(results, args.out, args.no_studies)
    except KeyboardInterrupt:  # in the studies or while writing: the JSON and the report are replaced whole
        print("dyncheck: interrupted", file=sys.stderr)
        return 130
    except OSError as error:  # the output passed its checks before the run but failed now (a full disk)
        where = f"--json {args.json}" if args.command == "run" else f"--out {args.out}"
        return error_exit(f"{where}: cannot write it: {error.strerror or error}")
    if interrupted:
        print(f"dyncheck: interrupted during case {interrupted}; " + (
            f"above are the {len(results)} cases that finished" if args.command == "run"
            else f"the report in {args.out}/ is unchanged"), file=sys.stderr)
        return 130
    return 0 if all(r["status"] in OK_STATUSES for res in results for r in res["rows"]) else 1


def error_exit(error):
    # on one line: the engines' parse errors span several
    print(f"dyncheck: error: {' '.join(str(error).split())}", file=sys.stderr)
    return 2


def run_cases(cases):
    """The results of the cases, and the name of the case that Ctrl-C stopped (None if none did)."""
    results = []
    try:
        for case in tqdm(cases, desc="checks", unit="case", disable=None, leave=False):
            results.append(run_case(case))
    except KeyboardInterrupt:
        return results, cases[len(results)].name
    return results, None


def make_report(results, out, no_studies):
    from dyncheck.report import write_reports
    start = time.perf_counter()
    for res in results:
        res["studies"] = None if no_studies else study_case(res["case"])
    written = write_reports(results, out)
    print(f"studies and pages: wrote {len(written)} files to {out}/ in {time.perf_counter() - start:.1f} s")
    print_results(results, table=False)


def study_case(case):
    """The case's work-precision sweep and stability studies, with a progress bar (they take minutes)."""
    from dyncheck import stability, work_precision
    with tqdm(desc=f"studies of {case.name}", unit="run", disable=None, leave=False) as bar:
        def progress(text):
            bar.set_postfix_str(text[-60:], refresh=False)
            bar.update()
        return {"work_precision": work_precision.sweep(case, progress),
                "stability": stability.studies(case, progress)}


def list_cases():
    rows = []
    for name in case_names():
        case = load_case(name)
        rows.append({"case": name, "section": case.section, "title": case.title,
                     "coordinates": ", ".join(case.coords) or "-", "reactions": ", ".join(case.reaction_names)})
    print(pd.DataFrame(rows).to_string(index=False))
    return 0


def parse_overrides(pairs):
    overrides = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        name, value = name.strip(), value.strip()
        if not sep or not name:
            raise ValueError(f"--set '{pair}': expected NAME=VALUE")
        if name in overrides:
            raise ValueError(f"--set {name}: given twice ({name}={overrides[name]} and {name}={value}); give it once")
        if not value.isascii():  # float() reads Arabic-Indic or fullwidth digits: a value nobody typed as a number
            raise ValueError(f"--set {name}={value}: not a number in ASCII digits")
        overrides[name] = value
    return overrides


def select_cases(names, set_pairs):
    names = list(dict.fromkeys(names)) or case_names()  # a case named twice runs once
    defaults = {name: load_case(name).defaults for name in names}  # an unknown case name is named here
    overrides = parse_overrides(set_pairs)
    for key in overrides:
        if not any(key in d for d in defaults.values()):
            known = sorted({p for d in defaults.values() for p in d})
            raise ValueError(f"--set {key}: no selected case has a parameter '{key}'{suggest(key, known)} "
                             f"(cases: {', '.join(names)})")
    cases = [load_case(name, **{k: v for k, v in overrides.items() if k in defaults[name]}) for name in names]
    for case in cases:  # load every model and study setting now: a scene that disagrees with its case,
        for source in SOURCES:  # or a setting that is vacuous or runs away, is bad input
            case.model(source)
        stability.validate(case)
        work_precision.settings(case)
    return cases


def format_rows(rows):
    table = pd.DataFrame(rows)[TABLE_COLUMNS]
    for column in ("error", "tolerance"):
        table[column] = table[column].map(lambda x: "-" if x is None or pd.isna(x) else f"{x:.2e}")
    return table


def print_results(results, table=True):
    for res in results:
        case, rows = res["case"], res["rows"]
        if table:
            print(f"\n== {case.name} ({case.section}) {case.title}"
                  + (f"  [overrides: {case.overrides}]" if case.overrides else ""))
            print(format_rows(rows).to_string(index=False))
        counts = pd.Series([r["status"] for r in rows]).value_counts().to_dict()
        summary = ", ".join(f"{n} {s}" for s, n in sorted(counts.items()))
        print(f"{case.name}: {summary} ({res['wall']:.1f} s)")


def to_json(results):
    keys = ("check", "quantity", "sources", "error", "tolerance", "ceiling", "status", "finding", "detail")
    return {"cases": [{"case": res["case"].name, "section": res["case"].section,
                       "params": res["case"].params,
                       "checks": [{k: r[k] for k in keys} for r in res["rows"]],
                       "findings": findings_of(res)} for res in results]}


def check_json_path(path):
    if path.exists() and not path.is_file():
        raise ValueError(f"--json {path}: is not a regular file")
    check_writable("--json", path, [path.parent])


def check_out_folder(out):
    """The report replaces `out` as a whole (see report.write_reports): refuse a folder that holds
    anything but a report, so that `--out .` cannot swap away a source tree."""
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {out}: is not a folder")
    if out.is_dir() and any(out.iterdir()) and not (out / "index.md").is_file():
        raise ValueError(f"--out {out}: holds files but no report (no index.md), and the report replaces the "
                         "whole folder; give a new or empty folder, or one that holds a report")
    out = out.resolve()  # the parent of where a symbolic link points: there the new report is built
    check_writable("--out", out, [out.parent] + ([out] if out.is_dir() else []))


def check_writable(option, path, folders):
    """Before any work: create the folders and write a file in each (permission bits do not tell:
    a read-only mount, /proc, root); ValueError naming `option`, `path` and why."""
    not_a_folder = next((p for p in path.parents if p.exists() and not p.is_dir()), None)
    if not_a_folder:
        raise ValueError(f"{option} {path}: {not_a_folder} is a file, not a folder")
    for folder in folders:
        try:
            folder.mkdir(parents=True, exist_ok=True)
            with tempfile.TemporaryFile(dir=folder):
                pass
        except OSError as error:
            raise ValueError(f"{option} {path}: cannot write in {folder}: {error.strerror or error}") from None


def write_json(data, path):
    """Whole or not at all: written beside `path`, synced to disk, then renamed over it, so a full
    disk or a kill leaves the previous file as it was."""
    partial = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        with open(partial, "w") as file:
            file.write(json.dumps(data, indent=2) + "\n")
            file.flush()
            os.fsync(file.fileno())
        os.replace(partial, path)
    finally:
        partial.unlink(missing_ok=True)


if __name__ == "__main__":
    sys.exit(main())
