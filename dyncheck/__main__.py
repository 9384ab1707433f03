"""The console command `dyncheck` (and `python -m dyncheck`): dyncheck.cli, whose imports (numpy, SciPy, pandas,
the engines: seconds) are interruptible like the rest of the command: Ctrl-C during them ends it with one line and
exit 130, as it does later (dyncheck.cli.main)."""

import sys


def entry():
    try:
        from dyncheck import cli
    except KeyboardInterrupt:
        print("dyncheck: interrupted", file=sys.stderr)
        sys.exit(130)
    cli.entry()


if __name__ == "__main__":
    entry()
