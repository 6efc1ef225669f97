"""The ``dlasweep`` console command's entry: Ctrl-C while the command's modules load ends it in one line.

``cli`` loads numpy, numba and netCDF (about 1.5 s); an interrupt then
would otherwise print a traceback. The package's own ``__init__`` loads
nothing heavy, so this module runs before any of it.
"""

import os
import sys


def run() -> None:
    """Load ``cli`` and run the command (``cli.run``); exit 130 with one line on Ctrl-C while loading."""
    try:
        from .cli import run as main
    except KeyboardInterrupt:
        command = sys.argv[1] if len(sys.argv) > 1 and not sys.argv[1].startswith("-") else ""
        print(f"dlasweep {command}".rstrip() + ": interrupted", file=sys.stderr, flush=True)
        os._exit(130)
    main()
