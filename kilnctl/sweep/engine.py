"""Running a study: executors (local processes, in-process, Dask), the point cache, progress.

The engine checks every point's parameters first, looks each point up in the
cache, and sends only the missing ones to the executor.  Every finished point
is written to the cache as it arrives (one small JSON file, written whole or
not at all), so an interrupted sweep resumes where it stopped.  The result
table lists the points in the space's order, whatever order they finished in,
so the same study gives the same table on any executor.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import sys
import threading
import time
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from concurrent.futures import as_completed as _local_as_completed
from pathlib import Path

from ..errors import KilnctlError, ParameterError, WorkerError
from ..files import write_atomic
from ..simulate import simulate

__all__ = ["run_sweep", "run_point", "PointCache", "EXECUTORS", "SweepInterrupted"]


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped a sweep: the workers are ended; the message says how many points are cached.

    A :class:`KeyboardInterrupt`, so code that catches that keeps working.
    """

#: executor names accepted besides ``dask://HOST:PORT`` and a ``distributed.Client``
EXECUTORS = ("local", "serial")


def run_point(task: dict) -> dict:
    """Simulate one point of a study and return its record (runs in a worker).

    Parameters
    ----------
    task : dict
        From :meth:`Study.task`.

    Returns
    -------
    dict
        ``key``; ``status`` ``'ok'`` or ``'failed'``; ``error`` (the
        :class:`~kilnctl.errors.KilnctlError` message of a failed point, else
        ``''``); ``summary`` (:meth:`Response.summary`, JSON-ready); ``custom``
        (values of the study's own output functions).

    Notes
    -----
    A point that fails with a :class:`~kilnctl.errors.KilnctlError` (an
    unstable loop, an event storm, gains that cannot be designed) is a result,
    recorded with its message; any other exception is a bug and stops the
    sweep.
    """
    from ..params import Parameters

    rec = {"key": task["key"], "status": "ok", "error": "", "summary": {}, "custom": {}}
    try:
        resp = simulate(Parameters(task["params"]), components=task["structure"], t_end=task["t_end"],
                        **task["options"])
        rec["summary"] = resp.summary()
        rec["custom"] = {k: float(f(resp)) for k, f in task["custom"].items()}
    except KilnctlError as exc:
        rec.update(status="failed", error=f"{type(exc).__name__}: {exc}")
    return rec


class PointCache:
    """Finished points on disk: one JSON file per point, named by its key.

    The key hashes the full parameter set, model, horizon, components,
    simulation options and the kilnctl sources that decide the result (see
    :func:`kilnctl.sweep.study.code_fingerprint`); any study reaching the same
    point reuses it.

    Parameters
    ----------
    directory : path-like
        Folder of the cache (created when the first point is stored).
    """

    def __init__(self, directory):
        self.directory = Path(directory)
        if self.directory.exists() and not self.directory.is_dir():
            raise ParameterError(f"cache {self.directory} is a file, not a folder")

    def path(self, key: str) -> Path:
        """Return the file of a point: ``<directory>/<key[:2]>/<key>.json``."""
        return self.directory / key[:2] / f"{key}.json"

    def get(self, key: str) -> dict | None:
        """Return the stored record of a point, or None (also for an unreadable file)."""
        try:
            rec = json.loads(self.path(key).read_text())
        except (OSError, ValueError):
            return None
        return rec if isinstance(rec, dict) and rec.get("key") == key else None

    def put(self, record: dict) -> Path:
        """Store a point's record, whole or not at all; return its file."""
        return write_atomic(self.path(record["key"]), json.dumps(record))


# --- executors ----------------------------------------------------------------------------------
def _init_worker() -> None:
    """Worker start: leave Ctrl-C to the parent, which shuts the pool down cleanly."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def _sigint_ignored():
    """Ignore SIGINT in this block (main thread only; elsewhere a no-op), then restore the handler."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


class _Lazy(Future):
    """A future run in this process when its result is first asked for (the 'serial' executor)."""

    def __init__(self, fn, arg):
        super().__init__()
        self._call = (fn, arg)

    def result(self, timeout=None):
        if not self.done():
            fn, arg = self._call
            try:
                self.set_result(fn(arg))
            except BaseException as exc:
                self.set_exception(exc)
        return super().result(timeout)


class _Serial:
    label = "serial"

    def submit(self, task):
        return _Lazy(run_point, task)

    def as_completed(self, futures):
        return iter(futures)

    def close(self, futures, cancel: bool):
        pass


class _Local:
    def __init__(self, workers: int):
        import multiprocessing

        self.label = f"local ({workers} process{'es' if workers > 1 else ''})"
        # spawn: clean workers (no inherited threads or locks); each builds its plants once and is reused
        self.pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                                        initializer=_init_worker)

    def submit(self, task):
        # the pool starts its workers inside submit; they start with Ctrl-C ignored (an ignored signal stays
        # ignored across exec), so a Ctrl-C while one is importing cannot print a worker traceback
        with _sigint_ignored():
            return self.pool.submit(run_point, task)

    def as_completed(self, futures):
        return _local_as_completed(futures)

    def close(self, futures, cancel: bool):
        if not cancel:
            self.pool.shutdown(wait=True)
            return
        # interrupted: end the workers now rather than wait for their running points (a point can take
        # minutes, and the pool's shutdown could wait on a worker forever). The pool keeps its processes
        # in a private dict; Python 3.14 has ProcessPoolExecutor.terminate_workers for this.
        procs = list((getattr(self.pool, "_processes", None) or {}).values())
        # the pool's manager thread, finding its workers gone and its pipes closed, can die with "OSError: [Errno
        # 9] Bad file descriptor" (a test run printed it after "kilnctl sweep: interrupted"): that thread's
        # exception is not the user's business, and it is waited for so nothing prints after the message
        manager = getattr(self.pool, "_executor_manager_thread", None)
        hook = threading.excepthook
        threading.excepthook = lambda args: None if args.thread is manager else hook(args)
        try:
            self.pool.shutdown(wait=False, cancel_futures=True)
            for proc in procs:
                proc.terminate()
            for proc in procs:
                proc.join(timeout=5)
                if proc.is_alive():
                    proc.kill()
                    proc.join(timeout=5)
            if manager is not None:
                manager.join(timeout=5)
        finally:
            threading.excepthook = hook


class _Dask:
    def __init__(self, executor):
        try:
            import distributed
        except ImportError:
            raise KilnctlError("a Dask executor needs the 'distributed' package: pip install 'kilnctl[sweep]'") \
                from None
        self._as_completed = distributed.as_completed
        if isinstance(executor, str):
            address = "tcp://" + executor.split("://", 1)[1]
            try:
                self.client = distributed.Client(address, timeout=10)
            except OSError as exc:
                raise KilnctlError(f"cannot reach the Dask scheduler at {address}: {exc}") from None
            self.own = True
        else:
            self.client, self.own = executor, False
        self.label = f"dask ({self.client.scheduler.address})"

    def submit(self, task):
        return self.client.submit(run_point, task, key=f"kilnctl-sweep-{task['key']}")

    def as_completed(self, futures):
        return self._as_completed(list(futures))

    def close(self, futures, cancel: bool):
        if cancel and futures:
            self.client.cancel(list(futures))
        if self.own:
            self.client.close()


def _executor(executor, workers):
    """Check the executor arguments; return a function that opens the backend for n tasks."""
    if executor is None or executor == "local":
        if workers is None:
            workers = os.cpu_count() or 1
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
            raise ParameterError(f"workers = {workers!r} must be an integer >= 1")
        return lambda n: _Local(min(workers, n))
    if workers is not None:
        raise ParameterError("workers= applies to the local executor only; a Dask cluster has its own workers")
    if executor == "serial":
        return lambda n: _Serial()
    if isinstance(executor, str) and executor.startswith(("dask://", "tcp://")) \
            or not isinstance(executor, str) and hasattr(executor, "submit") and hasattr(executor, "scheduler"):
        return lambda n: _Dask(executor)
    raise ParameterError(f"executor = {executor!r}: use 'local', 'serial', 'dask://HOST:PORT' or a "
                         "dask.distributed.Client")


def _progress(total: int, name: str, enabled: bool, cached: int):
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=name, unit="run", disable=not enabled, file=sys.stderr, dynamic_ncols=True,
                postfix={"cached": cached} if cached else None)


def run_sweep(study, executor=None, *, workers: int | None = None, cache=None, progress: bool = True,
              confirm: bool = True):
    """Run every point of a study in parallel and return the labelled result table.

    Parameters
    ----------
    study : Study
        What to simulate.
    executor : str or dask.distributed.Client, optional
        ``'local'`` (default): a pool of ``workers`` long-lived processes on
        this machine; ``'serial'``: one after the other in this process;
        ``'dask://HOST:PORT'``: the Dask scheduler at that address; or a
        ``dask.distributed.Client`` (kept open).  Every executor gives the same
        table.
    workers : int, optional
        Processes of the local executor (default: the number of cores).
    cache : path-like, optional
        Folder of finished points.  Points found there are not run again, and
        each point is stored as soon as it finishes, so an interrupted sweep
        resumes.  None: no cache.
    progress : bool, default True
        Show a progress bar (on standard error).
    confirm : bool, default True
        Re-run the point with the largest first output on the CVODES engine
        at rtol 1e-10 and keep the comparison in ``result.worst_point``
        (:func:`kilnctl.sweep.confirm.confirm_worst`): a sweep's worst case
        must be a property of the plant, not of the integrator.

    Returns
    -------
    SweepResult
        One row per point, in the space's order.

    Raises
    ------
    ParameterError
        Impossible points (before anything runs) or a bad executor.
    SweepInterrupted
        (a :class:`KeyboardInterrupt`) on Ctrl-C, after the worker processes
        are ended; the finished points stay cached.
    WorkerError
        A local worker process ended abruptly (most often: the calling
        script's code is not under ``if __name__ == "__main__":``).
    """
    from .result import SweepResult

    t0 = time.perf_counter()
    open_backend = _executor(executor, workers)
    params = study.parameter_sets()
    tasks = [study.task(p) for p in params]
    store = PointCache(cache) if cache is not None else None
    records: dict[str, dict] = {}
    from_cache: set[str] = set()
    if store is not None:
        for t in tasks:
            if t["key"] not in records:
                rec = store.get(t["key"])  # the key covers the custom outputs' names
                if rec is not None:
                    records[t["key"]] = rec
                    from_cache.add(t["key"])
    todo = list({t["key"]: t for t in tasks if t["key"] not in records}.values())
    label = "none (all points cached)"
    if todo:
        backend = open_backend(len(todo))
        label = backend.label
        futures = {}
        try:
            with _progress(len(todo), study.name, progress, len(from_cache)) as bar:
                futures = {backend.submit(t): t["key"] for t in todo}
                for fut in backend.as_completed(futures):
                    rec = fut.result()
                    records[futures[fut]] = rec
                    if store is not None:
                        store.put(rec)
                    bar.update()
        except BrokenProcessPool:
            backend.close(futures, cancel=True)
            raise WorkerError.abrupt(f"run_sweep of study {study.name!r} on {label}", "executor='serial'") from None
        except KeyboardInterrupt:
            backend.close(futures, cancel=True)
            done = sum(t["key"] in records for t in tasks)
            raise SweepInterrupted(
                "nothing written" + (f"; {done} of {len(tasks)} points are in the cache {store.directory}: "
                                     "run again to resume" if store is not None else "")) from None
        except BaseException:
            backend.close(futures, cancel=True)
            raise
        backend.close(futures, cancel=False)
    info = {
        "n_points": len(tasks),
        "n_computed": len(todo),
        "n_cached": len(from_cache),
        "n_failed": sum(records[t["key"]]["status"] != "ok" for t in tasks),
        "wall_s": time.perf_counter() - t0,
        "executor": label,
        "cache": None if store is None else str(store.directory),
    }
    cached = [t["key"] in from_cache for t in tasks]
    result = SweepResult.from_records(study, [records[t["key"]] for t in tasks], cached, info)
    if confirm:
        from .confirm import confirm_worst

        result.worst_point = confirm_worst(study, result)
        result.info["wall_s"] = time.perf_counter() - t0
    return result

