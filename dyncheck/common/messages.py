"""The words every message shares: the one line that refuses bad input, naming the file, the field and the
value (`field_error`), a suggestion for a misspelt name, a count with its noun, counts of statuses, the engines by
name."""

import difflib

ENGINE_NAMES = {"mujoco": "MuJoCo", "pinocchio": "Pinocchio"}  # as the pages write the sources mujoco, pinocchio


def suggest(word, choices):
    """" (did you mean 'x'?)" for the choice closest to a misspelt word, or ""."""
    close = difflib.get_close_matches(word, list(choices), n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def field_error(file, field, value, problem):
    """The ValueError refusing `value` of `field` in `file`: "case.toml: integration.rtol = 0.5 is above ..."."""
    text = repr(value)
    return ValueError(f"{file}: {field} = {text if len(text) <= 80 else text[:77] + '...'} {problem}")


def hint(word, choices):
    """A suggestion for a misspelt `word`, or else the choices."""
    return suggest(word, choices) or f"; expected one of: {', '.join(choices)}"


def plural(n, noun):
    """"1 case", "6 cases"."""
    return f"{n} {noun}" + ("s" if n != 1 else "")


NOUN_STATUSES = ("finding", "runaway")  # of dyncheck.results.values.Status; the others read as verbs or adjectives


def statuses_in_words(counts):
    """{status: n} in words, those with none left out: "58 pass, 16 findings, 1 fail"."""
    return ", ".join(plural(n, status) if status in NOUN_STATUSES else f"{n} {status}"
                     for status, n in counts.items() if n)


class WithBlock(ValueError):
    """A refusal of bad input whose message is one line, and `block`: lines to paste (a case.toml table) that the
    command prints after it as they are."""

    def __init__(self, message, block):
        super().__init__(message)
        self.block = block
