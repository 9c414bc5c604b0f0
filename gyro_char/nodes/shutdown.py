"""
Orderly stop of a node process on SIGINT or SIGTERM, at any instant.

rclpy's own signal handlers shut the context down from a signal thread while the node may still
be inside a callback or a worker thread: the node can then no longer publish, log or write its
last checkpoint, and a worker thread still inside C++ code (HiGHS in the noise fit, pocketfft in
the simulator) when the interpreter exits aborts the process ("terminate called without an active
exception", exit 134). The node processes therefore initialise rclpy without its handlers and
install these instead: a signal only sets ``STOP``. The spin loop sees it within one wait period,
the node cancels and joins its workers (they poll ``STOP``), writes its last checkpoint, and only
then are the node and the context torn down (exit 0).

Pure computations whose result is worthless once the process stops (generating a simulated run)
run inside ``STOP.interruptible()``: there a signal raises ``Interrupted`` at once.

A process that is still alive ``EXIT_DEADLINE_S`` after the first stop signal (a teardown stuck
in C++ code, where no Python check runs) prints every thread's stack to stderr and exits with
code 1: ``faulthandler``'s watchdog runs in its own C thread, without the GIL.

Standard library only, so that the executables (``gyro_char.nodes.entry``) install the handlers
before the heavy imports, which take seconds on a loaded machine.
"""
import contextlib
import faulthandler
import signal
import sys
import threading
from typing import Iterator, Optional


class Interrupted(BaseException):
    """Raised inside ``StopSignal.interruptible`` when a stop signal arrives (like Ctrl-C)."""


class StopSignal:
    """A process-wide stop request set by SIGINT / SIGTERM (or by ``request``)."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)
    EXIT_DEADLINE_S = 20.0

    def __init__(self) -> None:
        self._event = threading.Event()
        self._interruptible = 0
        self.installed = False
        self.signum: Optional[int] = None

    def install(self) -> None:
        """Handle SIGINT and SIGTERM from now on (main thread only; idempotent)."""
        if not self.installed:
            for sig in self.SIGNALS:
                signal.signal(sig, self._handle)
            self.installed = True

    def ignore_from_now(self) -> None:
        """
        Ignore SIGINT and SIGTERM: the process has stopped and only has to exit.

        The interpreter resets Python-level handlers to the default action while it exits, so
        a repeated signal in that last moment would kill the process (exit -15); ignored
        signals stay ignored.
        """
        if self.installed:
            for sig in self.SIGNALS:
                signal.signal(sig, signal.SIG_IGN)

    def _handle(self, signum: int, frame) -> None:
        if not self._event.is_set():  # the first signal arms the deadline, repeats do not
            faulthandler.dump_traceback_later(self.EXIT_DEADLINE_S, exit=True, file=sys.stderr)
        self.request(signum)
        if self._interruptible:
            raise Interrupted(signal.Signals(signum).name)

    def request(self, signum: Optional[int] = None) -> None:
        """Ask for a stop (what the signal handlers do)."""
        self.signum = signum
        self._event.set()

    def is_set(self) -> bool:
        """Return True once a stop was requested."""
        return self._event.is_set()

    def check(self) -> None:
        """Raise ``Interrupted`` when a stop was requested (for long loops in worker threads)."""
        if self._event.is_set():
            raise Interrupted('stop requested')

    @contextlib.contextmanager
    def interruptible(self) -> Iterator[None]:
        """Let a stop signal raise ``Interrupted`` inside this block (main thread only)."""
        self.check()
        self._interruptible += 1
        try:
            yield
        finally:
            self._interruptible -= 1


STOP = StopSignal()
