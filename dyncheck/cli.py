"""Command line: `dyncheck list | run | report | bench | campaign | new`.  Exit codes: 0 all pass, 1 a check failed,
2 bad input, 130 interrupted (Ctrl-C) (docs/statuses.md).

`run` and the studies produce results (dyncheck.results.values); `report` saves them beside the pages and
renders the pages from what it saved, so `report --from` renders the same pages from saved results
alone, without the engines."""

import argparse
import contextlib
import json
import os
import sys
import tempfile
import textwrap
import time
from dataclasses import replace
from importlib.metadata import version
from pathlib import Path

from dyncheck.case import isolation
from dyncheck.case.folder import CASES_DIR, SOURCES, case_names, load_case
from dyncheck.checks.pointwise import validate_placeholders
from dyncheck.checks.runs import QUICK_LEAVES_OUT, run_case, unfinished
from dyncheck.common.messages import suggest
from dyncheck.common.progress import Progress
from dyncheck.results import ci
from dyncheck.results.values import heading, load_results, rows_text, save_results, to_json
from dyncheck.run import cache
from dyncheck.run.simulate import fastest_frequency


def entry():
    """The console command: main() in a process of its own, so that a case's own code cannot end dyncheck with an
    exit code of its choosing (dyncheck.case.isolation.supervised)."""
    sys.exit(isolation.supervised(main))


def main(argv=None):
    """The command line; its exit code.  Ctrl-C, wherever it lands (loading the cases, a derivation's import, the
    studies, writing: the JSON and the report are replaced whole), ends it with one line and 130."""
    try:
        return command(argv)
    except KeyboardInterrupt:
        print("dyncheck: interrupted", file=sys.stderr)
        return 130


def command(argv):
    """The command line's command, run; its exit code."""
    start = time.perf_counter()
    parser = argparse.ArgumentParser(prog="dyncheck", description=__doc__)
    parser.add_argument("--version", action="version", version=f"dyncheck {version('dyncheck')}")
    commands = parser.add_subparsers(dest="command", required=True)
    listing = commands.add_parser("list", help="list the cases and their parameters")
    run = commands.add_parser("run", help="run the checks and print a table")
    report = commands.add_parser("report", help="run the checks and write Markdown reports with figures")
    bench = commands.add_parser("bench", help="throughput of each source and the harness's overhead")
    campaign = commands.add_parser("campaign", help="every source at many random parameter sets, and the stability "
                                                    "maps, on Dask (docs/campaign.md)")
    campaign.add_argument("case", metavar="CASE", help="the case")
    campaign.add_argument("--sets", required=True, metavar="N", help="random parameter sets")
    campaign.add_argument("--states", default="10", metavar="M", help="random states per set (default: 10)")
    campaign.add_argument("--workers", metavar="K", help="local Dask workers (default: the cores)")
    campaign.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask cluster's scheduler, instead")
    campaign.add_argument("--out", type=Path, metavar="DIR",
                          help="its chunks, page and maps (default: reports/campaigns/CASE)")
    campaign.add_argument("--chunk", default="100", metavar="SETS", help="sets per task (default: 100)")
    campaign.add_argument("--grid", default="8", metavar="N",
                          help="the stability maps' cells per axis (default: 8; 0: no maps)")
    campaign.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                          help="fix a parameter at a value (it is then not drawn)")
    new = commands.add_parser("new", help="start a case of your own from an MJCF scene (docs/own-case.md)")
    new.add_argument("name", metavar="NAME", help="the case's name, and its folder's")
    new.add_argument("--scene", type=Path, required=True, metavar="PATH", help="the scene, MJCF")
    new.add_argument("--cases", type=Path, default=Path("."), metavar="DIR", dest="cases_dir",
                     help="the folder of case folders to make it in (default: the current folder)")
    bench.add_argument("cases", nargs="*", metavar="CASE", help="cases to measure (default: all)")
    bench.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help=argparse.SUPPRESS)
    bench.add_argument("--runs", action="store_true",
                       help="also whole runs: the tight solutions' cache, the command `run --quick` against `run`, "
                            "and the cases in parallel (minutes)")
    listing.add_argument("cases", nargs="*", metavar="CASE", help="cases to list (default: all)")
    for sub in (run, report):
        sub.add_argument("cases", nargs="*", metavar="CASE", help="cases to run (default: all)")
        sub.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                         help="override a parameter in every selected case that has it")
        sub.add_argument("--junit", type=Path, metavar="PATH",
                         help="also write the rows as JUnit XML (a test suite per case, a test case per row)")
        sub.add_argument("--no-cache", action="store_true",
                         help="compute the tight solutions anew rather than take them from the cache of earlier runs")
    for sub in (listing, run, report, bench, campaign):
        sub.add_argument("--cases", type=Path, default=CASES_DIR, metavar="DIR", dest="cases_dir",
                         help="the folder of case folders (default: the checkout's cases/)")
    run.add_argument("--json", type=Path, metavar="PATH", help="also write the results as JSON")
    run.add_argument("--quick", action="store_true",
                     help="the checks at states alone, in seconds: pointwise, equations, printed rows, random "
                          "parameter sets, the terms a wrong equation lacks; leaves out every run along time "
                          f"(the rows of {', '.join(QUICK_LEAVES_OUT)})")
    run.add_argument("--results", type=Path, metavar="DIR",
                     help="also save the results (rows, runs, findings) for `dyncheck report --from DIR`")
    report.add_argument("--out", type=Path, metavar="DIR",
                        help="where to write the reports (default: reports, or with --set a folder beside it named "
                             "after the overrides, so that the book's pages stay as they are)")
    report.add_argument("--no-studies", action="store_true",
                        help="leave out the work-precision and stability studies (minutes) from the pages")
    report.add_argument("--no-animations", action="store_true",
                        help="leave out the animations (GIFs, seconds per case) from the pages")
    report.add_argument("--from", type=Path, metavar="DIR", dest="saved",
                        help="render the pages from results saved in DIR (a report's results/ folder, or "
                             "`run --results DIR`) instead of running anything; needs neither engine")
    args = parser.parse_args(argv)
    quick = args.command == "run" and args.quick
    if args.command == "report" and args.out is None:
        args.out = Path("reports" + "".join(f"-{pair.strip().replace('/', '_')}" for pair in args.set))
    if args.command == "campaign" and args.out is None:
        args.out = Path("reports") / "campaigns" / args.case
    for option in ("out", "junit", "json", "results", "saved", "cases_dir", "scene"):
        # from the current folder now: a case's code that changes it (os.chdir) cannot move where the command writes
        if getattr(args, option, None) is not None:
            setattr(args, option, getattr(args, option).absolute())
    isolation.RECORD.loading = True  # until the cases are loaded, a case's code that ends the process is bad input
    try:
        if args.command == "list":
            return list_cases(args.cases, args.cases_dir)
        if args.command == "new":
            return new_case(args.name, args.scene, args.cases_dir)
        if args.command == "campaign":
            return campaign_command(args)
        if args.command in ("run", "report") and args.junit:
            check_file_path("--junit", args.junit)
        if args.command == "report":
            check_out_folder(args.out)
            if args.saved:
                return report_saved(args, start)
        cases = select_cases(args.cases, args.set, args.cases_dir, quick)
        cache.enabled = not getattr(args, "no_cache", False)
        if args.command == "run" and args.json:
            check_file_path("--json", args.json)
        if args.command == "run" and args.results:
            if quick:  # the pages that report --from renders draw the runs along time
                raise ValueError(f"--results {args.results}: saves what `report --from` renders pages from, with the "
                                 "runs along time that --quick leaves out; give one or the other")
            check_results_folder(args.results, [case.name for case in cases])
    except ValueError as error:
        return error_exit(error)
    isolation.RECORD.loading = False
    if args.command == "bench":
        from dyncheck.bench import bench_table
        print(bench_table(cases, run_cases if args.runs else None))
        return 0
    try:
        # The findings' localisation (seconds each) only where it is shown: in JSON, results, pages.
        results, interrupted = run_cases(cases, args.command == "report" or bool(args.json or args.results),
                                         quick=quick)
        writing = f"--out {args.out}" if args.command == "report" else None  # for a write that fails
        if args.command == "run":
            print_results(results, quick=quick)
            if args.json:
                writing = f"--json {args.json}"
                write_json(to_json(results, ci.tool_versions(), interrupted, QUICK_LEAVES_OUT if quick else ()),
                           args.json)
            if args.results and not interrupted:
                writing = f"--results {args.results}"
                save_results(results, args.results)
        elif not interrupted:  # a report of some cases would pass for one of all
            results = make_report(results, cases, args.out, args.no_studies, not args.no_animations)
        if not interrupted:  # a JUnit file has no word for "some cases did not run": it would pass for all
            writing = f"--junit {args.junit}"  # the one file that close() writes
            close(results, args.junit, start, quick)
    except OSError as error:  # the output passed its checks before the run but failed now (a full disk)
        return error_exit(f"{writing}: cannot write it: {error.strerror or error}")
    if interrupted:
        print(f"dyncheck: interrupted during case {interrupted}; " + (
            f"above are the {len(results)} cases that finished" if args.command == "run"
            else f"the report in {args.out}/ is unchanged"), file=sys.stderr)
        return 130
    return exit_code(results)


def exit_code(results):
    return 0 if all(r.status.ok for result in results for r in result.rows) else 1


def error_exit(error):
    # on one line (the engines' parse errors span several), and then what it gives to paste (messages.WithBlock)
    print(f"dyncheck: error: {' '.join(str(error).split())}", file=sys.stderr)
    if getattr(error, "block", None):
        print(error.block, file=sys.stderr)
    return 2


def run_cases(cases, localise=True, workers=None, quick=False):
    """The results of the cases (with `quick`, of their checks at states: run_case), in their order, and the name of
    the first case that did not finish because of Ctrl-C (None if all did).  Each case runs in a forked process of
    its own (it inherits its Case, whose engine models cannot be pickled), one per core, the longest first
    (expected_cost) so that no long case starts last; a process that dies or overruns its budget gives its case one
    failing row saying so (dyncheck.case.isolation)."""
    workers = min(len(cases), workers or os.cpu_count() or 1)
    finished = {}  # index -> result
    try:
        with Progress("checks", total=len(cases), unit="case") as bar:
            def done(index, result):
                finished[index] = result
                bar.step()
                bar.note(f"{result.name} done, {result.status}")
            longest_first = sorted(range(len(cases)), key=lambda i: -expected_cost(cases[i]))
            each = isolation.each_forked([cases[i] for i in longest_first],
                                         lambda case: run_case(case, localise, quick), workers, shared_memory(workers))
            with contextlib.closing(each):  # on Ctrl-C, its processes are ended here
                for position, (kind, value) in each:
                    index = longest_first[position]
                    if kind != "interrupted":  # an interrupted case is named as such, not given a row
                        done(index, value if kind == "result" else unfinished(cases[index], value))
    except KeyboardInterrupt:
        pass
    unfinished_names = [case.name for index, case in enumerate(cases) if index not in finished]
    return [finished[index] for index in sorted(finished)], (unfinished_names[0] if unfinished_names else None)


def shared_memory(workers):
    """A case's budget (isolation.Budget) with, where its case file sets none, an equal share of the machine's
    memory among `workers` processes at once."""
    memory = isolation.machine_memory() // workers
    return lambda case: replace(case.budget, memory=case.budget.memory or memory)


def expected_cost(case):
    """A case's checks' cost, roughly: how many radians of its fastest motion it integrates (omega t_end)."""
    return (fastest_frequency(case) or 0.0) * case.initial[2]


def make_report(results, cases, out, no_studies, animations=True):
    """The studies of each case added to its results, and the pages written (with `animations`, their GIFs);
    the results."""
    from dyncheck.pages.report import write_reports
    start = time.perf_counter()
    results = results if no_studies else studied(results, cases)
    written = write_pages(results, out, animations)
    print(f"studies and pages: wrote {len(written)} files to {out}/ in {time.perf_counter() - start:.1f} s")
    print_results(results, table=False)
    return results


def write_pages(results, out, animations):
    """dyncheck.pages.report.write_reports, as a stage with its progress (a minute or more, with the animations)."""
    from dyncheck.pages.report import write_reports
    with Progress(f"pages to {out}/", total=len(results), unit="case") as bar:
        def written(name):
            bar.step()
            bar.note(f"{name} written")
        return write_reports(results, out, animations, written)


def report_saved(args, start):
    """`report --from DIR`: the pages of the results saved in DIR, with no run."""
    if args.cases or args.set or args.no_studies:
        raise ValueError("--from renders saved results as they are: give no CASE, --set or --no-studies with it")
    results = load_results(args.saved)
    written = write_pages(results, args.out, not args.no_animations)
    print(f"pages: wrote {len(written)} files to {args.out}/ from {args.saved}/")
    print_results(results, table=False)
    close(results, args.junit, start)
    return exit_code(results)


def close(results, junit, start, quick=False):
    """What every finished run and report ends with: the JUnit file (with --junit), an annotation per
    failing row on GitHub Actions, the failing rows and the summary line (which says `quick`: run --quick's)."""
    if junit:
        write_file(ci.junit_xml(results), junit)
    if os.environ.get("GITHUB_ACTIONS") == "true":  # GitHub sets it in every step of a workflow
        for line in ci.github_annotations(results):
            print(line)
    for line in ci.recap(results, time.perf_counter() - start, quick):
        print(line)


def studied(results, cases):
    """The results with each case's studies (study_case), a case per forked process, one per core, the longest
    first, as run_cases runs the checks (the studies take minutes).  A case whose checks did not finish (no runs:
    dyncheck.checks.runs.unfinished) has no studies; one whose studies did not finish keeps its checks, and
    stderr says why."""
    todo = sorted((i for i, result in enumerate(results) if result.runs), key=lambda i: -expected_cost(cases[i]))
    out = list(results)
    with Progress("studies", total=len(todo), unit="case") as bar:
        workers = min(len(todo), os.cpu_count() or 1) or 1
        each = isolation.each_forked([cases[i] for i in todo], study_case, workers, shared_memory(workers))
        with contextlib.closing(each):
            for position, (kind, value) in each:
                index = todo[position]
                if kind == "interrupted":
                    raise KeyboardInterrupt
                bar.step()
                if kind == "result":
                    out[index] = results[index].with_studies(value)
                    bar.note(f"{cases[index].name} done")
                else:
                    bar.say(f"dyncheck: the studies of {cases[index].name} did not finish, its page has none: {value}")
    return out


def study_case(case):
    """The case's work-precision sweep, stability studies and Campbell diagram."""
    from dyncheck.studies import campbell, stability, work_precision
    return {"work_precision": work_precision.sweep(case, step), "stability": stability.studies(case, step),
            "vibration": campbell.sweep(case, step)}


def step(text=""):
    """A study's step, in a process of its own: the stage's progress counts whole cases."""


def campaign_command(args):
    """`dyncheck campaign`: its input checked before any cluster starts (ValueError: exit 2), then the campaign."""
    from dyncheck.pages import campaign_page
    from dyncheck.studies import campaign
    sets, states, chunk, grid = (whole_number(option, value, least) for option, value, least in
                                 (("--sets", args.sets, 1), ("--states", args.states, 1), ("--chunk", args.chunk, 1),
                                  ("--grid", args.grid, 0)))
    workers = whole_number("--workers", args.workers, 1) if args.workers is not None else os.cpu_count() or 1
    case = load_case(args.case, args.cases_dir, **parse_overrides(args.set))
    check_writable("--out", args.out.resolve(), [args.out.resolve()])
    if not case.spec["sample"].get("params"):
        raise ValueError(f"{case.origin}: no [sample.params]: the case draws no random parameter sets")
    plan = campaign.plan(case, sets, states, chunk, args.out)
    try:
        table, drawn, wall, workers, computed = campaign.command(case, plan, grid, workers, args.scheduler)
    except KeyboardInterrupt:
        print(f"dyncheck: interrupted; the finished chunks are in {plan.folder}/, a restart computes the others",
              file=sys.stderr)
        return 130
    page, timing = campaign_page.write(case, plan, table, drawn, wall, workers, computed)
    failed = table["status"].isin(campaign_page.FAILED)
    print(f"campaign {case.name}: {table['set'].nunique()} sets, {int(failed.sum())} failing rows; "
          f"{page}, {timing}; chunks in {plan.folder}/")
    return 1 if failed.any() else 0


def whole_number(option, text, least):
    """`text` as an integer >= least, or ValueError naming the option."""
    try:
        number = int(text.strip())
    except ValueError:
        raise ValueError(f"{option} {text}: not a whole number") from None
    if number < least:
        raise ValueError(f"{option} {text}: must be at least {least}")
    return number


def list_cases(names, cases_dir):
    """Each case (all, or those named) with its parameters: value, unit, the values it allows and the
    range its random parameter sets are drawn from."""
    for name in list(dict.fromkeys(names)) or case_names(cases_dir):
        case = load_case(name, cases_dir)
        print(f"\n== {name}: {heading(case.spec)}\n"
              f"coordinates: {', '.join(case.coords) or '-'}; reactions: {', '.join(case.reaction_names) or '-'}")
        ranges = case.spec["sample"].get("params", {}).get("ranges", {})
        rows = [{"parameter": p.name, "value": f"{p.value:g}", "unit": p.unit or "-",
                 "allowed": p.allowed,
                 "sampled": "-" if p.name not in ranges else
                 " to ".join(f"{case.value(end):g}" for end in ranges[p.name]), "about": p.about}
                for p in case.parameters]
        print(text_table(rows) if rows else "no parameters")
        constraints = case.spec.get("constraints", [])
        if constraints:
            print("constraints, which every set of values (the case file's and --set's together) must keep:")
            print(text_table([{"constraint": f"{c['expression']} {'>' if c.get('strict') else '>='} 0",
                               "here": f"{case.value(c['expression']):.3g}", "why": " ".join(c["why"].split())}
                              for c in constraints]))
    print("\n" + textwrap.fill("allowed: what a value (the case file's or --set's) must satisfy; sampled: the "
                               "interval that the random parameter sets are drawn from (the 'random parameters' "
                               "check), - if the parameter is not drawn; here: a constraint's value at the "
                               "case's numbers, how far they are from breaking it", 100))
    return 0


def new_case(name, scene, cases_dir):
    """`dyncheck new`: the folder cases_dir/name with the scene copied and equations.py and case.toml to fill in."""
    from engines.mjcf import describe
    from dyncheck.case.derived import EQUATIONS, SCENE
    from dyncheck.case.scaffold import scaffold
    if not name.isidentifier():
        raise ValueError(f"new {name}: a case's name is an identifier (letters, digits and _, not starting with a digit)")
    folder = cases_dir / name
    if folder.exists():
        raise ValueError(f"new {name}: {folder} exists; choose another name or remove it")
    if not scene.is_file():
        raise ValueError(f"--scene {scene}: no such file")
    equations, case_toml = scaffold(name, describe(scene))
    folder.mkdir(parents=True)
    (folder / SCENE).write_bytes(scene.read_bytes())
    (folder / EQUATIONS).write_text(equations)
    (folder / "case.toml").write_text(case_toml)
    print(f"made {folder}/ with {SCENE}, {EQUATIONS} and case.toml: write the equations in {folder / EQUATIONS}, "
          f"then `dyncheck run {name} --cases {cases_dir}` (docs/own-case.md)")
    return 0


def text_table(rows, width=100):
    """Rows of strings as left-aligned columns; the last column wraps so that lines stay within `width`
    where the other columns leave it room."""
    columns = list(rows[0])
    widths = {c: max(len(c), *(len(r[c]) for r in rows)) for c in columns[:-1]}
    indent = sum(widths.values()) + 2 * len(widths)
    last = max(width - indent, 30)
    lines = []
    for row in [dict(zip(columns, columns))] + rows:
        wrapped = textwrap.wrap(row[columns[-1]], last) or [""]
        lines.append("".join(f"{row[c]:<{widths[c]}}  " for c in columns[:-1]) + wrapped[0])
        lines += [" " * indent + more for more in wrapped[1:]]
    return "\n".join(lines)


def parse_overrides(pairs):
    overrides = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        name, value = name.strip(), value.strip()
        if not sep or not name:
            raise ValueError(f"--set '{pair}': expected NAME=VALUE")
        if name in overrides:
            raise ValueError(f"--set {name}: given twice ({name}={overrides[name]} and {name}={value}); give it once")
        overrides[name] = value
    return overrides


def select_cases(names, set_pairs, cases_dir=CASES_DIR, quick=False):
    """The cases named (default: all of cases_dir), with the overrides of `set_pairs`, loaded and checked: ValueError
    (bad input) where one is.  `quick`: for `run --quick`, whose checks at states need none of the settings of the
    runs along time and the studies, which are then not checked (nor their modules imported)."""
    names = list(dict.fromkeys(names)) or case_names(cases_dir)  # a case named twice runs once
    defaults = {name: load_case(name, cases_dir).defaults for name in names}  # an unknown case name is named here
    overrides = parse_overrides(set_pairs)
    for key in overrides:
        if not any(key in d for d in defaults.values()):
            known = sorted({p for d in defaults.values() for p in d})
            raise ValueError(f"--set {key}: no selected case has a parameter '{key}'{suggest(key, known)} "
                             f"(cases: {', '.join(names)})")
    cases = [load_case(name, cases_dir, **{k: v for k, v in overrides.items() if k in defaults[name]})
             for name in names]
    for case in cases:  # load every model and setting now: a scene that disagrees with its case,
        for source in SOURCES:  # or a setting that is vacuous or runs away, is bad input
            case.model(source)
        validate_placeholders(case)
        if not quick:
            validate_studies(case)
    return cases


def validate_studies(case):
    """A case's settings of its vibration analysis and its studies checked: ValueError where one is vacuous or runs
    away."""
    from dyncheck.checks import linear
    from dyncheck.studies import stability, work_precision
    stability.validate(case)
    linear.validate(case)
    work_precision.settings(case)


def print_results(results, table=True, quick=False):
    """Each case's table of rows (with `table`), where its random states lie, and with `quick` what the quick tier
    left out; its wrong equations and its summary line."""
    for result in results:
        spec, rows = result.spec, result.rows
        if table:
            print(f"\n== {result.name}: {heading(spec)}"
                  + (f", with {result.overrides_text}" if result.overrides else ""))
            print(rows_text(rows))
            print(ci.states_covered(result))
            if quick:
                print(f"{result.name}: quick tier, the checks at states alone: left out every run along time, the rows "
                      f"of {', '.join(QUICK_LEAVES_OUT)} (`dyncheck run` without --quick has them)")
        for line in ci.wrong_equations(result):
            print(line)
        print(f"{result.name}: {result.status}: {ci.tally(rows)} ({result.wall:.1f} s)")


def check_file_path(option, path):
    if path.exists() and not path.is_file():
        raise ValueError(f"{option} {path}: is not a regular file")
    check_writable(option, path, [path.parent])


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


def check_results_folder(folder, names):
    """`run --results` replaces folder/<case>/ for each case: refuse a folder of something else."""
    if folder.exists() and not folder.is_dir():
        raise ValueError(f"--results {folder}: is not a folder")
    if folder.is_dir() and any(folder.iterdir()) and not any(folder.glob("*/value.json")):
        raise ValueError(f"--results {folder}: holds files but no saved results (no <case>/value.json); "
                         "give a new or empty folder, or one `run --results` wrote")
    for name in names:
        own = folder / name
        if own.is_symlink() or (own.exists() and not (own / "value.json").is_file()):
            raise ValueError(f"--results {folder}: {own} is not saved results, and the run would replace it")
    check_writable("--results", folder.resolve(), [folder.resolve()])


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
    write_file(json.dumps(data, indent=2) + "\n", path)


def write_file(text, path):
    """Whole or not at all: written beside `path`, synced to disk, then renamed over it, so a full
    disk or a kill leaves the previous file as it was."""
    partial = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        with open(partial, "w", encoding="utf-8") as file:
            file.write(text)
            file.flush()
            os.fsync(file.fileno())
        os.replace(partial, path)
    finally:
        partial.unlink(missing_ok=True)


if __name__ == "__main__":
    sys.exit(main())
