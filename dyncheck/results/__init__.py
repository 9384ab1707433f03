"""Stage 1, the typed values the stages hand on, and their saving: the rows, outcomes, findings and a case's
whole result, their JSON and table (values), the deterministic store (store), the numbers a page's prose cites,
measured from the results (measured), what a CI system reads of a run (ci: versions, JUnit, annotations).  The
checks and studies write these values, the pages read them: so they come before both.  Imports only
dyncheck.common.  The names of values are importable from here, as docs/results.md documents them
(`dyncheck.results.load_results`)."""

from dyncheck.results.values import (OWN_WORDS, RESULTS_VERSION, CaseResult, Failure, Finding, Frames, Localisation,
                                     Outcome, Pair, Row, Status, StudyResult, case_json, format_rows, load_result,
                                     load_results, save_results, to_json)

__all__ = ["OWN_WORDS", "RESULTS_VERSION", "CaseResult", "Failure", "Finding", "Frames", "Localisation", "Outcome",
           "Pair", "Row", "Status", "StudyResult", "case_json", "format_rows", "load_result", "load_results",
           "save_results", "to_json"]
