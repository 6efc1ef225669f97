"""The ``dlasweep`` console command's entry: Ctrl-C at any moment ends it in one line.

A command loads numpy, numba and netCDF, which takes a noticeable moment: ``cli`` itself,
then the modules of the command (``loading``); an interrupt then would
otherwise print a traceback. The package's own ``__init__`` loads nothing
heavy, so this module runs before any of it.
"""

import _thread
import atexit
import contextlib
import os
import signal
import sys
import threading
import time

REDELIVERY_SECONDS = 0.05
"""How long an ignored Ctrl-C waits to be raised again: the main thread has long left the hook by then."""


def run() -> None:
    """Run the command (``cli.main``) and exit with its status; 130 with one line on a Ctrl-C that ``cli``
    did not catch.

    The process ends without tearing the interpreter down: freeing the modules
    a command loads (numba and LLVM, dask, pandas) at exit takes about as long
    as a small sweep's clusters take to grow (docs/performance.md, "The command
    and its start"). By the time ``main`` returns
    every file is closed; the exit handlers still run and the output is flushed
    before the process ends.
    """
    sys.unraisablehook = _deliver_again(sys.unraisablehook)
    try:
        with loading():
            from .cli import main
        code = main()
    except KeyboardInterrupt:
        print(f"{command_of(sys.argv[1:])}: interrupted", file=sys.stderr, flush=True)
        os._exit(130)
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError):  # a closed pipe, a closed stream
            stream.flush()
    os._exit(code)


@contextlib.contextmanager
def loading():
    """Within, Ctrl-C is noted as well as raised, and raised again on leaving when a module loading
    swallows it (rarely, and with no trace: docs/performance.md) or turns it into
    another error (``RuntimeError`` from a class's ``__set_name__``): the command would otherwise run on.

    Only in the main thread, where Ctrl-C is not ignored (a shell's background job ignores it)."""
    noted = []
    handler = signal.getsignal(signal.SIGINT)

    def note(signum, frame):
        noted.append(signum)
        handler(signum, frame)

    noting = handler is signal.default_int_handler and threading.current_thread() is threading.main_thread()
    if noting:
        signal.signal(signal.SIGINT, note)
    try:
        yield
    except Exception:
        if not noted:
            raise
    finally:
        if noting:
            signal.signal(signal.SIGINT, handler)
    if noted:
        raise KeyboardInterrupt


def command_of(argv) -> str:
    """The command a command line names, before it is parsed: ``dlasweep grow``, or ``dlasweep``."""
    return f"dlasweep {argv[0]}" if argv and not argv[0].startswith("-") else "dlasweep"


def _deliver_again(hook):
    """``hook``, except that a Ctrl-C raised where Python must ignore it is raised again in the main thread.

    Python raises ``KeyboardInterrupt`` in whatever code runs when the
    signal arrives. In a weakref callback or a ``__del__`` (an import lock
    freed while the modules load, say) it can only print "Exception
    ignored" and go on, and the command then ran to its end: 1 in about 200
    interrupts while loading. It is raised again from another thread a
    moment later: raised at once, it would land in this hook and be
    ignored as well.
    """
    def deliver_again(unraisable):
        if unraisable.exc_type is not None and issubclass(unraisable.exc_type, KeyboardInterrupt):
            _thread.start_new_thread(_interrupt_main_soon, ())
        else:
            hook(unraisable)
    return deliver_again


def _interrupt_main_soon():
    time.sleep(REDELIVERY_SECONDS)
    _thread.interrupt_main()
