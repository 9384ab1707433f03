"""Progress of the long stages (the checks, the studies, the pages, a campaign's chunks and maps), on stderr: stdout's
rows and summary line are what tests and CI read, and stay as they are.

On a terminal it is a tqdm bar.  Elsewhere (a CI log, `nohup`, a redirect) a bar draws nothing, and `dyncheck report`
would be silent for many minutes; there it is plain lines instead: one as a stage starts, one per milestone that the
stage notes (a case's checks done, the next study), one as it ends, and between them, while steps go on without a
milestone, at most one every QUIET seconds."""

import sys
import time

from tqdm import tqdm

QUIET = 60.0  # seconds: off a terminal, the longest a stage's steps go without a line (a sweep takes minutes)


class Progress:
    """`with Progress("checks", total=6, unit="case") as bar:` then `bar.step(text)` for each step done (a run, a
    chunk) and `bar.note(text)` for a milestone.  An exception leaving the block (Ctrl-C) ends it without the
    closing line."""

    def __init__(self, what, total=None, unit="run", initial=0):
        self.what, self.total, self.unit, self.count = what, total, unit, initial
        self.start = self.last = time.monotonic()
        self.bar = tqdm(total=total, initial=initial, desc=what, unit=unit, leave=False) if on_terminal() else None
        if self.bar is None:
            self.say(f"dyncheck: {what} ...")

    def step(self, text=""):
        """One step done; `text` (what it was) shown on the bar, or in the next line that QUIET lets through."""
        self.count += 1
        if self.bar is not None:
            self.bar.set_postfix_str(text[-60:], refresh=False)
            self.bar.update()
        elif time.monotonic() - self.last >= QUIET:
            self.say(f"dyncheck: {self.what}: {self.counted()}{', ' + text if text else ''} ({self.elapsed()})")

    def note(self, text):
        """A milestone: a line of its own off a terminal, the bar's description on one."""
        if self.bar is not None:
            self.bar.set_description(f"{self.what}: {text}", refresh=False)
        else:
            self.say(f"dyncheck: {self.what}: {text} ({self.elapsed()})")

    def counted(self):
        return f"{self.count}/{self.total} {self.unit}s" if self.total else f"{self.count} {self.unit}s"

    def elapsed(self):
        return f"{time.monotonic() - self.start:.1f} s"

    def say(self, line):
        print(line, file=sys.stderr, flush=True)
        self.last = time.monotonic()

    def __enter__(self):
        return self

    def __exit__(self, kind, error, traceback):
        if self.bar is not None:
            self.bar.close()
        elif kind is None:
            counted = f"{self.counted()}, " if self.count or self.total else ""  # a stage without steps: its time
            self.say(f"dyncheck: {self.what} done ({counted}{self.elapsed()})")


def on_terminal():
    """Whether stderr is a terminal (tqdm's own test, `disable=None`)."""
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):  # no stderr, or a closed one
        return False
