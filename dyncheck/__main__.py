"""The console command `dyncheck` (and `python -m dyncheck`): dyncheck.cli, whose imports (numpy, SciPy, pandas,
the engines: seconds) are interruptible like the rest of the command: Ctrl-C during them ends it with one line and
exit 130, as it does later (dyncheck.cli.main)."""

import os
import sys


def entry():
    try:
        from dyncheck import cli
    except KeyboardInterrupt:
        print("dyncheck: interrupted", file=sys.stderr, flush=True)
        # Not sys.exit: where Ctrl-C landed in code that an extension module's import runs through the C API, the
        # interpreter marks it unhandled and, on exiting, kills itself by SIGINT (exit -2) whatever was caught since.
        os._exit(130)
    cli.entry()


if __name__ == "__main__":
    entry()
