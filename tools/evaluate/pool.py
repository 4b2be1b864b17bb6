"""Where in-process runs of a sweep happen: a pool of worker processes here, or Dask tasks.

Why worker processes that live for the whole sweep: an in-process run of the tiny scene is a
fraction of a second of simulation, and importing chronav and loading its numba kernels is
seconds.  A worker pays that once and then runs run after run with warm imports, caches and
compiled kernels (``runs_in_worker`` in each result says how many it ran).  Processes, not threads:
the agents are Python, one core each.

On Dask a task is one run (``dask_task``): it first checks that the worker has the scene files
the client has (SHA-256 of the scene and its agenda file) and the same chronav, so a cluster whose
machines drifted apart gives an error naming the file or version instead of other numbers.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import socket
import threading
import time
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from pathlib import Path
from typing import Any

from tools.evaluate.sweep import RunSpec, execute_run, failed_result, run_isolated

_STOP: Any = None          # the pool's stop event, in a worker process
_RUNS = 0                  # runs this worker process has done


def _worker_init(stop: Any) -> None:
    """Ctrl-C goes to the sweep, which stops the runs through ``stop`` (the run ends cleanly)."""
    global _STOP
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _STOP = stop


def run_in_worker(spec_data: dict[str, Any], runs_dir: str, timeout_s: float, record: bool = True) -> dict[str, Any]:
    """One in-process run in this (long-lived) worker process."""
    global _RUNS
    spec = RunSpec.from_dict(spec_data)
    # Recorded whatever the sweep's environment says (the report links each run), unless --no-record.
    os.environ["RERUN"] = "on" if record else "off"
    started = time.monotonic()
    try:
        result = execute_run(spec, Path(runs_dir), timeout_s, mode="in-process", stop=_STOP, record=record)
    except Exception as exc:  # noqa: BLE001 - a run that could not run is a result, not a crash
        return failed_result(spec, f"{type(exc).__name__}: {exc}")
    _RUNS += 1
    return {**result, "task_wall_s": time.monotonic() - started, "worker_pid": os.getpid(), "runs_in_worker": _RUNS}


def default_jobs() -> int:
    """All cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


class InProcessPool:
    """``jobs`` worker processes, each running in-process runs one after the other."""

    def __init__(self, jobs: int, record: bool = True) -> None:
        self.jobs, self.record = jobs, record
        context = multiprocessing.get_context("spawn")   # no fork of a process holding threads
        self._stop = context.Event()
        self._pool = ProcessPoolExecutor(max_workers=jobs, mp_context=context, initializer=_worker_init,
                                         initargs=(self._stop,))

    def results(self, specs: Sequence[RunSpec], runs_dir: Path, timeout_s: float) -> Iterator[dict[str, Any]]:
        futures: dict[Future[dict[str, Any]], RunSpec] = {
            self._pool.submit(run_in_worker, spec.to_dict(), str(runs_dir), timeout_s, self.record): spec
            for spec in specs}
        running = set(futures)
        while running:
            done, running = wait(running, return_when=FIRST_COMPLETED)
            for future in done:
                try:
                    yield future.result()
                except Exception as exc:  # noqa: BLE001 - a worker died (BrokenProcessPool): report, go on
                    yield failed_result(futures[future], f"the worker process failed: {type(exc).__name__}: {exc}")

    def interrupt(self) -> None:
        """Runs under way end at their next round (interrupted, not in the ledger); queued ones never start."""
        self._stop.set()
        self._pool.shutdown(wait=False, cancel_futures=True)

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)


# ---------------------------------------------------------------------------------------------
# Dask.
# ---------------------------------------------------------------------------------------------

class WorkerMismatch(RuntimeError):
    """The worker's scene files or chronav differ from the client's."""


def sweep_fingerprint(scene: str) -> dict[str, Any]:
    """What a worker must share with the client for a run of ``scene``: chronav's version and the
    SHA-256 of the scene file and its agenda file."""
    from tools.evaluate.report import chronav_version, scene_files

    return {"chronav": chronav_version(), "files": scene_files(Path(scene))}


def check_worker(expected: dict[str, Any], scene: str) -> None:
    """WorkerMismatch naming the file or version that differs on this worker."""
    host = socket.gethostname()
    try:
        found = sweep_fingerprint(scene)
    except Exception as exc:  # noqa: BLE001 - e.g. the scene file is not on this machine
        raise WorkerMismatch(f"worker {host} cannot read scene {scene}: {exc}") from None
    if found["chronav"] != expected["chronav"]:
        raise WorkerMismatch(f"worker {host} runs chronav {found['chronav']}, the sweep {expected['chronav']}: "
                             "install the same chronav on every worker")
    theirs = {f["file"]: f["sha256"] for f in found["files"]}
    for entry in expected["files"]:
        if theirs.get(entry["file"]) != entry["sha256"]:
            raise WorkerMismatch(f"worker {host}: {entry['file']} differs from the sweep's (SHA-256 "
                                 f"{theirs.get(entry['file'], 'missing')} != {entry['sha256']}): copy the sweep's "
                                 "scene files to every worker")


def dask_task(spec_data: dict[str, Any], runs_dir: str, timeout_s: float, mode: str,
              expected: dict[str, Any], record: bool = True) -> dict[str, Any]:
    """One run on a Dask worker: checked, then in the worker itself (in-process) or as a launch."""
    spec = RunSpec.from_dict(spec_data)
    check_worker(expected, spec.scene)
    if mode != "in-process":
        return run_isolated(spec_data, runs_dir, timeout_s, record=record)
    # As in a launch's run (run_isolated): recorded whatever the worker's environment says, unless --no-record.
    os.environ["RERUN"] = "on" if record else "off"
    started = time.monotonic()
    result = execute_run(spec, Path(runs_dir), timeout_s, mode="in-process", stop=threading.Event(), record=record)
    return {**result, "task_wall_s": time.monotonic() - started, "worker_pid": os.getpid()}
