"""The words every message shares: a suggestion for a misspelt name, a count with its noun, counts of
statuses, the engines by name."""

import difflib

ENGINE_NAMES = {"mujoco": "MuJoCo", "pinocchio": "Pinocchio"}  # as the pages write the sources mujoco, pinocchio


def suggest(word, choices):
    """" (did you mean 'x'?)" for the choice closest to a misspelt word, or ""."""
    close = difflib.get_close_matches(word, list(choices), n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def plural(n, noun):
    """"1 case", "6 cases"."""
    return f"{n} {noun}" + ("s" if n != 1 else "")


NOUN_STATUSES = ("finding", "runaway")  # of dyncheck.results.values.Status; the others read as verbs or adjectives


def statuses_in_words(counts):
    """{status: n} in words, those with none left out: "58 pass, 16 findings, 1 fail"."""
    return ", ".join(plural(n, status) if status in NOUN_STATUSES else f"{n} {status}"
                     for status, n in counts.items() if n)
