"""Command line: `dyncheck list | run | report`.  Exit codes: 0 all pass, 1 a check failed, 2 bad input."""

import argparse
import json
import sys
import time
from pathlib import Path

import mujoco
import pandas as pd
from tqdm import tqdm

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
    except ValueError as error:  # on one line: the engines' parse errors span several
        print(f"dyncheck: error: {' '.join(str(error).split())}", file=sys.stderr)
        return 2
    if args.command == "bench":
        from dyncheck.bench import bench_case
        table = pd.concat([bench_case(case) for case in cases], ignore_index=True)
        table["ratio to bare"] = table["ratio to bare"].map(lambda x: "-" if pd.isna(x) else f"{x:.3g}")  # no bare loop
        print(table.to_string(index=False, float_format=lambda x: f"{x:.3g}"))
        return 0
    results = [run_case(case) for case in tqdm(cases, desc="checks", unit="case", disable=None, leave=False)]
    if args.command == "run":
        print_results(results)
        if args.json:
            write_json(results, args.json)
    else:
        from dyncheck.report import write_reports
        start = time.perf_counter()
        for res in results:
            res["studies"] = None if args.no_studies else study_case(res["case"])
        written = write_reports(results, args.out)
        print(f"studies and pages: wrote {len(written)} files to {args.out}/ in {time.perf_counter() - start:.1f} s")
        print_results(results, table=False)
    return 0 if all(r["status"] in OK_STATUSES for res in results for r in res["rows"]) else 1


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
        if not sep or not name:
            raise ValueError(f"--set '{pair}': expected NAME=VALUE")
        overrides[name.strip()] = value.strip()
    return overrides


def select_cases(names, set_pairs):
    names = names or case_names()
    defaults = {name: load_case(name).defaults for name in names}  # an unknown case name is named here
    overrides = parse_overrides(set_pairs)
    for key in overrides:
        if not any(key in d for d in defaults.values()):
            known = sorted({p for d in defaults.values() for p in d})
            raise ValueError(f"--set {key}: no selected case has a parameter '{key}'{suggest(key, known)} "
                             f"(cases: {', '.join(names)})")
    cases = [load_case(name, **{k: v for k, v in overrides.items() if k in defaults[name]}) for name in names]
    for case in cases:  # load every model now: a scene that disagrees with its case is bad input
        for source in SOURCES:
            case.model(source)
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
    keys = ("check", "quantity", "sources", "error", "tolerance", "status", "finding")
    return {"cases": [{"case": res["case"].name, "section": res["case"].section,
                       "params": res["case"].params,
                       "checks": [{k: r[k] for k in keys} for r in res["rows"]],
                       "findings": findings_of(res)} for res in results]}


def write_json(results, path):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(to_json(results), indent=2) + "\n")


if __name__ == "__main__":
    sys.exit(main())
