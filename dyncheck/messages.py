"""The words every message shares: a suggestion for a misspelt name, a count with its noun."""

import difflib


def suggest(word, choices):
    """" (did you mean 'x'?)" for the choice closest to a misspelt word, or ""."""
    close = difflib.get_close_matches(word, list(choices), n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def plural(n, noun):
    """"1 case", "6 cases"."""
    return f"{n} {noun}" + ("s" if n != 1 else "")
