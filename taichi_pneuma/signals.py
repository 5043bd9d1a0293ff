"""How the commands answer SIGINT (Ctrl-C), SIGTERM and SIGHUP: all three alike.

    interrupting()   for a command's whole run: each raises Interrupted (a KeyboardInterrupt naming the
                     signal), which the command turns into one `error: interrupted (<signal>)` line and the
                     exit code 128 + signal number (130 Ctrl-C, 143 SIGTERM, 129 SIGHUP)
    stopping()       during a ramp: the first asks it to stop (an Event is set, its .signum the signal; the ramp
                     asks it between Newton iterations and ends after the increments done); a second
                     interrupts at once. One that came too late for the ramp to see it (its last increment
                     was solved) is raised again as the block ends, to the handlers in place before it
    holding()        from the last solve to the last result file written: they wait for it (the handlers
                     only record them), then take their course
    ignored()        while a pool starts its workers: SIGINT and SIGHUP ignored, which the workers inherit
    quiet_while_loading()  called first by the package: when the program is one of its commands, a signal
                     before the command has set its own handlers (while the modules load) ends it with one
                     error line and 128 + signal, not a traceback of the imports; finished() when its run
                     is over: a signal while the interpreter shuts down changes nothing

Signal handlers belong to the main thread: in any other thread these change nothing.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from contextlib import contextmanager

NAMES: dict[int, str] = {signal.SIGINT: "Ctrl-C", signal.SIGTERM: "SIGTERM"}
if hasattr(signal, "SIGHUP"):
    NAMES[signal.SIGHUP] = "SIGHUP"


class Interrupted(KeyboardInterrupt):
    """A signal of NAMES asked the command to stop at once."""

    def __init__(self, signum: int = signal.SIGINT):
        super().__init__(signum)
        self.signum = signum


def name_of(exc: BaseException) -> str:
    """The signal that ended a run (a KeyboardInterrupt, or an exception given a .signum): 'Ctrl-C', 'SIGTERM', ..."""
    return NAMES.get(getattr(exc, "signum", signal.SIGINT), "a signal")


def exit_code_of(exc: BaseException) -> int:
    """128 + the number of the signal that ended a run, as shells report it."""
    return 128 + int(getattr(exc, "signum", signal.SIGINT))


def in_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextmanager
def handling(handler):
    """Each signal of NAMES handled by handler(signum) during the block (the main thread only); the handlers
    in place before are restored after it."""
    if not in_main_thread():
        yield
        return
    previous = {s: signal.signal(s, lambda signum, frame: handler(signum)) for s in NAMES}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, signal.SIG_DFL if h is None else h)


_held: list[int] | None = None  # the signals holding() holds, while it is active


def interrupt(signum: int) -> None:
    raise Interrupted(signum)


def interrupting():
    """Each signal of NAMES raises Interrupted during the block."""
    return handling(interrupt)


@contextmanager
def stopping():
    """Yield a threading.Event that the first signal of NAMES sets (recording it as .signum) instead of
    raising; a second one raises Interrupted at once. A signal the block's caller did not act on (the event
    set when the block ends without an exception: it came after the ramp's last check) is raised again after
    the block, to the handlers in place before it (holding()'s, where the files are being written). Outside
    the main thread the event never sets. A signal an enclosing holding() holds from before the block sets
    the event at once (a run of several ramps held for its files stops at the next ramp's start)."""
    requested = threading.Event()
    requested.signum = None
    if _held:  # held by an enclosing holding() before this ramp began (between two ramps): it stops at once
        requested.signum = _held.pop(0)
        requested.set()

    def first(signum: int) -> None:
        if requested.is_set():
            raise Interrupted(signum)
        requested.signum = signum
        requested.set()
        print(
            f"interrupt ({NAMES[signum]}): stopping, keeping the increments done (again to stop at once)",
            file=sys.stderr,
        )

    with handling(first):
        yield requested
    if requested.is_set():
        signal.raise_signal(requested.signum)


@contextmanager
def ignored():
    """SIGINT and SIGHUP ignored during the block (the main thread only): a process started in it (a pool's
    worker) starts ignoring them, so that a Ctrl-C to the whole process group while it loads its modules
    does not kill it (its parent decides what a Ctrl-C does to the runs)."""
    quiet = [s for s in NAMES if s != signal.SIGTERM]
    if not in_main_thread():
        yield
        return
    previous = {s: signal.signal(s, signal.SIG_IGN) for s in quiet}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, signal.SIG_DFL if h is None else h)


@contextmanager
def holding():
    """Signals of NAMES that arrive during the block (a finished run whose result files are being written) wait
    for its end; then each is raised again, to the handlers in place before the block. The handler only
    records the signal: nothing is raised inside the block, wherever (Python, Taichi or other native code) the
    signal finds the program. Nested blocks hold until the outermost ends."""
    global _held
    if _held is not None or not in_main_thread():
        yield
        return
    held = []
    _held = held

    def hold(signum: int) -> None:
        if not held:
            print(f"interrupt ({NAMES[signum]}): writing the result files first", file=sys.stderr)
        held.append(signum)

    try:
        with handling(hold):
            yield
    finally:
        _held = None
        for signum in dict.fromkeys(held):
            signal.raise_signal(signum)


def launched_as_command() -> bool:
    """Whether this program is one of the package's commands: python -m taichi_pneuma.apps.<name>, or a
    pneuma-<name> script."""
    argv = getattr(sys, "orig_argv", [])
    if "--multiprocessing-fork" in argv:  # a pool's worker (its sys.argv is its parent's)
        return False
    module = next((argv[i + 1] for i, arg in enumerate(argv[:-1]) if arg == "-m"), "")
    script = os.path.basename(sys.argv[0]) if sys.argv else ""
    return module.startswith("taichi_pneuma.apps.") or script.startswith("pneuma-")


def exit_quietly(signum: int) -> None:
    """One error line and exit 128 + signum at once: while the modules load nothing is written yet, and an
    exception could be swallowed (Taichi imports optional modules under a bare `except:`)."""
    print(f"error: interrupted ({NAMES[signum]})", file=sys.stderr)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(128 + signum)


def finished() -> None:
    """If the program is one of the commands, its run is over (files written, exit code decided): a signal
    from now on changes nothing (it would only come while the interpreter shuts down)."""
    if launched_as_command() and in_main_thread():
        for s in NAMES:
            signal.signal(s, signal.SIG_IGN)


def quiet_while_loading() -> None:
    """If the program is one of the commands, end it quietly (exit_quietly) on a signal of NAMES until the
    command sets its own handlers."""
    if launched_as_command() and in_main_thread():
        for s in NAMES:
            signal.signal(s, lambda signum, frame: exit_quietly(signum))
