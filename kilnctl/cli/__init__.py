"""The ``kilnctl`` command.

Each subcommand lives in its own module of this package as a subclass of
:class:`~kilnctl.cli.common.Command` (its options, its ``run``) and exposes
``register(subparsers)``, which adds its parser and sets ``func`` to a callable
taking the parsed arguments and returning an exit code.
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import importlib
import json
import os
import signal
import sys
import threading

from ..errors import KilnctlError

#: exit code of a run stopped by Ctrl-C (128 + SIGINT, as a shell reports it)
EXIT_INTERRUPTED = 130

#: subcommand modules, in the order ``kilnctl --help`` lists them
COMMANDS = ("params_cmd", "design_cmd", "simulate_cmd", "verify_cmd", "optimize_cmd", "compare_cmd",
            "diagnose_cmd", "split_cmd", "sweep_cmd")


class _Parser(argparse.ArgumentParser):
    """An argument parser that reports an unknown option with the usage of the subcommand it was given to.

    argparse hands the arguments a subcommand does not know back to the top-level
    parser, which would print ``usage: kilnctl [-h] COMMAND ...``; a user who
    typed ``kilnctl sweep --treshold`` needs the usage of ``sweep`` instead.
    """

    def parse_args(self, args=None, namespace=None):
        """Parse like argparse, but refuse unknown arguments with the subcommand's usage."""
        ns, extras = self.parse_known_args(args, namespace)
        if extras:
            where = self
            for action in self._actions:
                if isinstance(action, argparse._SubParsersAction):
                    where = action.choices.get(getattr(ns, action.dest, None), self)
            where.error("unrecognized arguments: " + " ".join(extras)
                        + f" (see {where.prog} --help)")
        return ns


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser with every available subcommand.

    Returns
    -------
    argparse.ArgumentParser
    """
    from .. import __version__

    parser = _Parser(prog="kilnctl", description="Control design and tuning of rotary-kiln drives.")
    parser.add_argument("--version", action="version", version=f"kilnctl {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"{__name__}.{name}":
                continue
            raise
        module.register(sub)
    return parser


def print_json(obj) -> None:
    """Print ``obj`` as indented JSON on standard output.

    Parameters
    ----------
    obj : object
        Anything ``json.dumps`` accepts.
    """
    json.dump(obj, sys.stdout, indent=2, allow_nan=False)
    sys.stdout.write("\n")


def _handled_exception(ident: int):
    """The exception the thread ``ident`` is handling now (in an ``except`` or ``finally``), or None."""
    exc = sys._current_exceptions().get(ident)
    if isinstance(exc, tuple):  # Python < 3.12: an exc_info triple
        exc = exc[1]
    return exc


class _Interrupts:
    """Ctrl-C raises KeyboardInterrupt once (clean-up runs); a second one ends the process at once.

    Some C wrappers clear any Python exception raised while they run, a KeyboardInterrupt included
    (seen with CasADi 3.8: SWIG's overload resolution calls back into Python and drops the errors; a
    Ctrl-C during the model build was ignored and the run went on).  So after the first Ctrl-C a watcher
    thread checks that the main thread is handling the KeyboardInterrupt, and raises it again in that
    thread if it is not.
    """

    #: seconds between the watcher's checks; three misses in a row make it raise again
    POLL = 0.1

    #: seconds the main thread has to run the Python handler after Ctrl-C before the process is ended from
    #: a helper thread (the main thread is then inside a long C computation that never checks for signals:
    #: seen with optimize-ramp pwl:12, minutes inside one CVODES sensitivity run)
    GRACE = 3.0

    def __init__(self, command: str = "kilnctl"):
        self.done = threading.Event()
        self.handled = threading.Event()  # the Python handler ran in the main thread
        self.ident = threading.get_ident()
        self.command = command
        self.wakeup_r = None
        self.saved_stderr = None  # the real sys.stderr, while the libraries' messages are silenced

    def first(self, signum, frame):
        self.handled.set()
        try:  # nothing here may fail: an exception other than KeyboardInterrupt would be dropped as well
            signal.signal(signal.SIGINT, self.second)
            self._silence_c_stderr()
            threading.Thread(target=self._watch, name="kilnctl-interrupt", daemon=True).start()
        finally:
            raise KeyboardInterrupt

    def second(self, signum, frame) -> None:  # pragma: no cover - runs in a process that ends here
        """Second Ctrl-C: end at once, whatever clean-up the first one started (worker processes too)."""
        import multiprocessing

        for child in multiprocessing.active_children():
            with contextlib.suppress(Exception):
                child.kill()
        os.write(2, b"kilnctl: interrupted again; stopped at once\n")
        os._exit(EXIT_INTERRUPTED)

    def start_wakeup_watch(self) -> int:
        """Watch SIGINT at the C level (``signal.set_wakeup_fd``), independently of the main thread.

        Returns
        -------
        int
            The previous wakeup file descriptor (to restore).
        """
        r, w = os.pipe()
        os.set_blocking(w, False)
        previous = signal.set_wakeup_fd(w, warn_on_full_buffer=False)
        self.wakeup_r, self.wakeup_w = r, w
        threading.Thread(target=self._wakeup_watch, name="kilnctl-sigint", daemon=True).start()
        return previous

    def _wakeup_watch(self) -> None:
        """The watcher thread: owns the read end of the wakeup pipe and closes it when it returns.

        Only this thread closes the read end: closed from :meth:`stop_wakeup_watch` while the thread
        had not yet reached ``os.read``, its number went to the next file the process opened and the
        thread's read took that file's first 64 bytes (seen once in the suite: a configuration file
        read back short).
        """
        try:
            self._wakeup_loop()
        finally:
            with contextlib.suppress(OSError):
                os.close(self.wakeup_r)

    def _wakeup_loop(self) -> None:
        presses = 0
        while True:
            try:
                data = os.read(self.wakeup_r, 64)
            except OSError:
                return
            if not data or self.done.is_set():
                return  # main() is done (woken by stop_wakeup_watch, or the write end closed)
            presses += data.count(bytes([signal.SIGINT]))
            if presses == 0:
                continue
            again = presses >= 2
            if again or not self.handled.wait(self.GRACE):
                if self.done.is_set():
                    return
                # a second Ctrl-C, or the main thread cannot run the handler (it is inside C code): end here
                import multiprocessing

                for child in multiprocessing.active_children():
                    with contextlib.suppress(Exception):
                        child.kill()
                msg = "kilnctl: interrupted again; stopped at once" if again else f"{self.command}: interrupted"
                os.write(2, (msg + "\n").encode())
                os._exit(EXIT_INTERRUPTED)

    def stop_wakeup_watch(self, previous: int) -> None:
        """Restore the previous wakeup descriptor and end the watcher thread.

        Only the write end is closed here; the watcher closes the read end itself as it returns
        (:meth:`_wakeup_watch`).
        """
        with contextlib.suppress(ValueError, OSError):
            signal.set_wakeup_fd(previous)
        with contextlib.suppress(OSError):
            os.write(self.wakeup_w, b"\0")  # wakes the watcher, which sees done and returns
        with contextlib.suppress(OSError):
            os.close(self.wakeup_w)

    def _silence_c_stderr(self) -> None:
        """Silence what the libraries print after Ctrl-C; kilnctl's own line goes to :attr:`stderr`.

        After Ctrl-C the libraries print their own view of it (CVODES through CasADi: "the right-hand
        side routine failed", "KeyboardInterruptException"; CasADi writes through Python's
        sys.stderr); the user asked to stop and gets one line from kilnctl instead.  Writers that
        hold the stream itself (a progress bar) still reach it.
        """
        try:
            self.saved_stderr = sys.stderr
            sys.stderr = open(os.devnull, "w")
        except OSError:
            self.saved_stderr = None

    def _watch(self):
        misses = 0
        while not self.done.wait(self.POLL):
            if isinstance(_handled_exception(self.ident), KeyboardInterrupt):
                misses = 0
                continue
            misses += 1
            if misses >= 3:
                ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(self.ident),
                                                           ctypes.py_object(KeyboardInterrupt))
                misses = 0

    @property
    def stderr(self):
        """Where kilnctl's own messages go: the real standard error even while it is silenced."""
        return sys.stderr if self.saved_stderr is None else self.saved_stderr

    def restore_stderr(self) -> None:
        """Undo :meth:`_silence_c_stderr` (for callers of :func:`main` that go on running)."""
        if self.saved_stderr is None:
            return
        with contextlib.suppress(OSError, ValueError):
            sys.stderr.close()
        sys.stderr = self.saved_stderr
        self.saved_stderr = None


def _mark_interrupt_handled() -> None:
    """Clear CPython's "unhandled KeyboardInterrupt" flag, so the process exits with our code, 130.

    CPython sets the flag when a KeyboardInterrupt leaves code run through ``PyRun_*`` (C extensions
    such as CasADi's SWIG wrappers do), even if Python code catches it later; at exit it then kills
    itself with SIGINT (status -2) instead of returning 130.  The flag is private: if it is not
    there, nothing is done.
    """
    with contextlib.suppress(ValueError, AttributeError):
        ctypes.c_int.in_dll(ctypes.pythonapi, "_Py_UnhandledKeyboardInterrupt").value = 0


@contextlib.contextmanager
def _interrupts():
    """Install the Ctrl-C handling of :class:`_Interrupts` for the block; yield it (or None).

    Installed only in the main thread, and the previous handler is put back on the way out (so
    calling :func:`main` in-process, as the tests do, leaves the caller's handling alone).
    """
    if threading.current_thread() is not threading.main_thread():
        yield None
        return
    state = _Interrupts()
    previous = signal.signal(signal.SIGINT, state.first)
    previous_wakeup = state.start_wakeup_watch()
    try:
        yield state
    finally:
        state.done.set()
        signal.signal(signal.SIGINT, previous)
        state.stop_wakeup_watch(previous_wakeup)
        state.restore_stderr()


def _caused_by_interrupt(exc: BaseException) -> bool:
    """True if a KeyboardInterrupt is in the cause or context chain of ``exc``."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def _interrupted(command: str, state, note: str) -> int:
    """Say ``<command>: interrupted`` on one line and give the exit code of a Ctrl-C."""
    if state is not None:
        state.done.set()
    out = sys.stderr if state is None else state.stderr
    print(f"{command}: interrupted" + (f"; {note}" if note else ""), file=out, flush=True)
    _mark_interrupt_handled()
    return EXIT_INTERRUPTED


def main(argv=None) -> int:
    """Run the ``kilnctl`` command line.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name; ``sys.argv[1:]`` by default.

    Returns
    -------
    int
        Exit code: 0 on success, 2 on a user error (message on stderr), 130
        when stopped by Ctrl-C (one line on stderr, no traceback; outputs are
        written whole or not at all, and a sweep's worker processes are
        ended).  A second Ctrl-C during the clean-up ends the process at once.
    """
    command = "kilnctl"
    with _interrupts() as state:
        try:
            args = build_parser().parse_args(argv)
            command = f"kilnctl {args.command}"
            if state is not None:
                state.command = command
            return int(args.func(args) or 0)
        except KeyboardInterrupt as exc:
            return _interrupted(command, state, str(exc))
        except BrokenPipeError:  # output piped into `head` and closed early (before `Exception`, which catches it too)
            sys.stderr.close()
            return 0
        except Exception as exc:
            # a Ctrl-C that lands in code which wraps it (an import creating a class: Python 3.11 turns an
            # exception in __set_name__ into a RuntimeError; a library turning it into its own error) is
            # still a Ctrl-C: exit 130 with the one line, not a traceback or "error"
            # so is any error after the Ctrl-C was handled: C code that ran the handler (CasADi calling back
            # into CVODES inside IPOPT) can report the KeyboardInterrupt as its own failure with the chain lost,
            # and stderr is silenced by then (exit 2 and nothing said, seen once in CI)
            if _caused_by_interrupt(exc) or (state is not None and state.handled.is_set()):
                return _interrupted(command, state, "")
            if isinstance(exc, KilnctlError):
                print(f"{command}: error: {exc}", file=sys.stderr)
                return 2
            raise


def run() -> None:  # pragma: no cover - ends the process
    """The ``kilnctl`` console script: :func:`main`, then the process ends with its exit code.

    After a Ctrl-C (exit code 130) the process ends without the interpreter's finalization: the interrupt
    may have left a C library (CasADi, CVODES) in the middle of a computation, and its clean-up at exit
    can abort the process (a CI run of the Ctrl-C test ended with status -6 after printing
    "kilnctl simulate: interrupted" and "Fatal Python error: PyThreadState_Get ... finalizing");
    everything kilnctl writes is written whole or removed by then.  ``kilnctl``, ``python -m kilnctl``
    and ``python -m kilnctl.cli`` all end here.
    """
    code = main()
    if code == EXIT_INTERRUPTED:
        for stream in (sys.stdout, sys.stderr, sys.__stderr__):
            with contextlib.suppress(Exception):
                stream.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    run()
