"""Ctrl-C and SIGTERM in the apps: one line saying what was kept and how to resume, exit code 130
(SIGINT) or 143 (SIGTERM), no traceback, wherever the run was.

The handlers (:func:`install_signal_handlers`) raise KeyboardInterrupt for SIGINT and
:class:`Terminated` (a KeyboardInterrupt) for SIGTERM, so that every cleanup written for Ctrl-C
(``finally``, atomic writes, joblib's abort, Lightning's teardown) runs for both; they also note
the signal, so that an interruption is reported as one whatever exception it became on its way
out (a numba kernel's ``SystemError``, Lightning's ``exit(1)`` after its graceful shutdown, a
joblib worker's error). :func:`guard` runs an app's entry and ends an interrupted run with the
line; what it says is set as the run goes (:func:`note`). Each app installs the handlers as its
first statement, before its slow imports (:func:`install_at_start`; :func:`guard` installs
them too); importing ``physics`` or any of its modules touches no signal handler.

Kept free of heavy imports: it runs before numpy, numba, torch or Hydra are loaded.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterable, Iterator
from typing import Any


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the program is, like Ctrl-C's KeyboardInterrupt."""


#: exit codes: 128 + the signal's number, as a shell reports a process the signal ended
EXIT_CODES = {signal.SIGINT: 130, signal.SIGTERM: 143}

#: the first of SIGINT or SIGTERM this process received (None: neither)
_SIGNAL: int | None = None
#: what an interrupted run has kept and how to resume, at this moment of the run
_NOTE: Callable[[], str] | None = None


#: where the app is: "start" (its imports, before :func:`guard`), "compose" (a Hydra app's
#: config being composed, until :func:`started`), "run" (its work), "done" (the app's entry
#: returned: its work is written, and a signal then is let be)
_PHASE = "start"
#: inside :func:`deferred`: a signal is noted and raised at the next :func:`check` instead
_DEFERRED = False


def _on_signal(signum: int, frame: Any) -> None:
    global _SIGNAL
    if _SIGNAL is None:
        _SIGNAL = signum
    if _PHASE in ("start", "compose"):  # nothing to clean up yet: end here at once; raised
        _report()  # inside a compiled module's import (torch's) it aborts the interpreter,
        os._exit(EXIT_CODES[signum])  # inside OmegaConf's composition it left a traceback
    if _PHASE == "done" or _DEFERRED:  # done (exit 0), or raised at the next check()
        return
    _raise(signum)


def _raise(signum: int) -> None:
    raise Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()


@contextlib.contextmanager
def deferred() -> Iterator[None]:
    """Within it a signal is noted and raised at the next :func:`check` (code that calls it at
    safe points, e.g. between training batches) or at its end, not wherever the program is: an
    exception raised inside a thread's queue operation (TensorBoard's event writer) leaves the
    writer thread waiting for ever, and the shutdown that joins it hangs; one raised inside a
    compiled module's import prints that import's traceback. A signal already noted is raised
    on entry."""
    check()
    with shielded():
        yield
    check()


@contextlib.contextmanager
def shielded() -> Iterator[None]:
    """Within it a signal is noted and not raised, also at its end: the cleanup of a run
    already interrupted (stopping its worker processes, removing its temporary files) runs
    whole when Ctrl-C comes again; :func:`guard` reports the interruption once."""
    global _DEFERRED
    before = _DEFERRED
    _DEFERRED = True
    try:
        yield
    finally:
        _DEFERRED = before


def check() -> None:
    """Raise the interruption a signal asked for, if one came (:func:`deferred`)."""
    if _SIGNAL is not None and _PHASE == "run":
        _raise(_SIGNAL)


def install_signal_handlers() -> None:
    """SIGINT raises KeyboardInterrupt and SIGTERM :class:`Terminated`; both note the signal.
    The interruption raised where Python cannot pass it on (a weakref callback or ``__del__``
    during garbage collection: matplotlib's transforms) is not printed as "Exception ignored"
    with its traceback (:func:`_unraisable`): :func:`guard` reports it once."""
    for signum in EXIT_CODES:
        signal.signal(signum, _on_signal)
    sys.unraisablehook = _unraisable


def _unraisable(args: Any) -> None:
    """``sys.unraisablehook``: a noted signal's interruption is let be; anything else as
    Python reports it."""
    if _SIGNAL is not None and isinstance(args.exc_value, KeyboardInterrupt):
        return
    sys.__unraisablehook__(args)


@contextlib.contextmanager
def _sigint_blocked() -> Iterator[None]:
    """SIGINT blocked in this thread within it, and in the processes it starts (a blocked
    signal stays blocked across fork and exec); one that came meanwhile is delivered at its
    end."""
    before = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)


def quiet_workers() -> None:
    """Make joblib's (loky's) worker processes deaf to Ctrl-C, which reaches the whole process
    group; the app's process alone answers: its joblib call stops the workers, and it reports
    once.

    - A worker starts with SIGINT blocked, from its first instruction on (loky starts it by
      fork and exec): one still importing would print a traceback of its own.
    - Loky stops its workers from a thread of its own through ``pgrep`` (without psutil),
      which starts with SIGINT blocked too: a second Ctrl-C would end ``pgrep``, the thread
      would die with a traceback and the workers run on, writing chunks after the app's line
      had said none was kept and keeping the app from exiting until they were killed."""
    from joblib.externals.loky import process_executor
    from joblib.externals.loky.backend import fork_exec as module

    for owner, name in ((module, "fork_exec"), (process_executor, "kill_process_tree")):
        original = getattr(owner, name)
        if not getattr(original, "_sigint_blocked", False):
            setattr(owner, name, _deaf(original))


def _deaf(call: Callable[..., Any]) -> Callable[..., Any]:
    """``call`` run with SIGINT blocked (:func:`_sigint_blocked`)."""
    def deaf(*args: Any, **kwargs: Any) -> Any:
        with _sigint_blocked():
            return call(*args, **kwargs)

    deaf._sigint_blocked = True  # type: ignore[attr-defined]
    return deaf


@contextlib.contextmanager
def worker_results(tasks: Iterable[Any], jobs: int) -> Iterator[Iterator[Any]]:
    """The results of joblib's ``delayed`` ``tasks`` run in ``jobs`` worker processes, each as
    it finishes (``return_as="generator_unordered"``), such that an interruption ends them
    whole and what the run then reports as kept is final (no worker writes after it):

    - the workers are deaf to Ctrl-C, loky's stopping of them too (:func:`quiet_workers`);
    - a signal while joblib starts them is raised once they run (:func:`deferred`): raised
      between a worker's start and joblib's record of it, it left that worker unknown to
      joblib, not stopped: it printed a traceback after the app's line;
    - when the block is left before every result was taken (Ctrl-C, SIGTERM, a task's error)
      the workers are stopped and reaped before the exception goes on, a further signal
      meanwhile noted, not raised (:func:`shielded`, :func:`_stop_workers`).
    """
    from joblib import Parallel

    quiet_workers()
    runs = None
    try:
        with deferred():
            runs = Parallel(n_jobs=jobs, return_as="generator_unordered")(tasks)
        yield runs
    except BaseException:
        with shielded():
            _stop_workers(runs)
        raise


def _stop_workers(runs: Iterator[Any] | None) -> None:
    """Stop joblib's call ``runs`` (None: not made) and every worker process this process
    started, and reap them, so that none is left behind, nor waited for when the interpreter
    exits. The workers are killed first, then joblib's generator is closed (a no-op where an
    exception inside it stopped it already): loky stopping them itself with tasks still
    queued, as right after the start, dropped the tasks and then read one, and its thread
    died with a traceback; a broken pool it gives up quietly."""
    import multiprocessing
    import warnings

    from joblib.externals.loky.backend.process import LokyProcess

    children = [c for c in multiprocessing.active_children() if isinstance(c, LokyProcess)]
    quiet_executor_manager()
    for child in children:
        with contextlib.suppress(ProcessLookupError):  # (loky's process has no kill())
            os.kill(child.pid, signal.SIGKILL)
    if runs is not None:
        with warnings.catch_warnings():  # joblib's note that it cancelled the other tasks
            warnings.simplefilter("ignore")
            runs.close()  # type: ignore[attr-defined]
    for child in children:
        child.join()
    for thread in threading.enumerate():  # its manager sees the pool broken and ends
        if thread.name.startswith(EXECUTOR_MANAGER) and thread is not threading.current_thread():
            thread.join(timeout=MANAGER_JOIN_S)


#: the name of loky's thread that feeds and watches its worker processes
EXECUTOR_MANAGER = "ExecutorManagerThread"
#: how long a stop waits for that thread to end [s]
MANAGER_JOIN_S = 5.0


def quiet_executor_manager() -> None:
    """From now on an exception in loky's executor-manager thread (:data:`EXECUTOR_MANAGER`)
    is not printed; every other thread's still is (:func:`threading.excepthook`). Called as
    the workers are killed on purpose: a manager that was queueing a task then reads the task
    the kill dropped and dies with a KeyError from its own thread, a traceback after the app's
    one line about what was kept (seen once in about ten Ctrl-C's as the first worker
    starts)."""
    previous = threading.excepthook
    if getattr(previous, "quiets_executor_manager", False):
        return

    def hook(args: threading.ExceptHookArgs) -> None:
        if args.thread is not None and args.thread.name.startswith(EXECUTOR_MANAGER):
            return
        previous(args)

    hook.quiets_executor_manager = True  # type: ignore[attr-defined]
    threading.excepthook = hook


def install_at_start(name: str) -> None:
    """The handlers, if the module named ``name`` (an app's ``__name__``) runs as the program
    (``python -m <app>``, ``python train.py``): an app calls it as its first statement, so that
    Ctrl-C and SIGTERM are handled during its slow imports. A module imported (by a test, by
    another program) installs nothing."""
    if name == "__main__":
        install_signal_handlers()


def interrupted(err: BaseException) -> bool:
    """Whether ``err`` ends an interrupted run (a signal came, or it is a KeyboardInterrupt)."""
    return _SIGNAL is not None or isinstance(err, KeyboardInterrupt)


def note(text: Callable[[], str] | None) -> None:
    """Set what an interruption from now on has kept (called when it happens)."""
    global _NOTE
    _NOTE = text


def _report() -> None:
    for signum in EXIT_CODES:  # the report and the exit are not interrupted again
        signal.signal(signum, signal.SIG_IGN)
    try:
        text = _NOTE() if _NOTE is not None else "nothing was written; run the command again"
    except Exception:  # the note is a courtesy; the exit code must come
        text = "run the command again"
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    print(f"interrupted: {text}", file=sys.stderr, flush=True)


def end() -> None:
    """One line saying what was kept and how to resume; exit 130 (SIGINT) or 143 (SIGTERM)."""
    _report()
    raise SystemExit(EXIT_CODES.get(_SIGNAL, 130))


def started() -> None:
    """The app's config is composed and nothing is made yet (:func:`guard`'s ``composing``):
    from now on a signal is raised where the program is, for its cleanups to run."""
    global _PHASE
    if _PHASE == "compose":
        _PHASE = "run"


def guard(main: Callable[[], Any], undo: Callable[[], None] | None = None, *,
          composing: bool = False) -> Any:
    """Run an app's entry ``main()``; an interrupted run ends with :func:`end`, also one that
    the code on its way swallowed the interruption of; ``undo()`` runs first (an app removes
    what a run interrupted before its work made). ``composing``: ``main`` composes a Hydra
    config first, which a signal ends at once, until :func:`started`."""
    global _PHASE
    install_signal_handlers()
    _PHASE = "compose" if composing else "run"
    try:
        try:
            result = main()
        except BaseException as err:
            if not interrupted(err):
                raise
            _undo_and_end(undo)
        if _SIGNAL is not None:
            _undo_and_end(undo)
    finally:
        _PHASE = "done"
    return result


def _undo_and_end(undo: Callable[[], None] | None) -> None:
    for signum in EXIT_CODES:
        signal.signal(signum, signal.SIG_IGN)
    if undo is not None:
        try:
            undo()
        except Exception:  # what stays is named by the note; the exit code must come
            pass
    end()
