"""``python -m ftcal``: the same as the ``ftcal`` command.

A Ctrl-C that arrives while Python is still importing the command line (before :func:`ftcal.cli.main` handles
signals) ends the run with status 130 and one line, as one arriving later does; left unhandled, CPython would
print a traceback and end the process by SIGINT itself (status -2), which is what an interrupted ``ftcal``
sometimes showed under load.
"""

import sys

if __name__ == "__main__":
    try:
        from .cli import main
    except KeyboardInterrupt:
        print("ftcal: interrupted", file=sys.stderr)
        sys.exit(130)
    sys.exit(main())
