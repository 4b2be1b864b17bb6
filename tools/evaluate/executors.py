"""Where a sweep's runs happen: on this machine (a pool of in-process workers, or a thread per
launch) or on a Dask cluster.

Why a module of its own: the executors drive the worker pool (tools/evaluate/pool.py), and the
pool's workers run single runs (tools/evaluate/sweep.py); with the executors in sweep.py the two
modules imported each other.  Now the order is one way: executors -> pool -> sweep.
"""

from __future__ import annotations

import os
import signal
import subprocess
import threading
import uuid
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from tools.evaluate.pool import InProcessPool, WorkerMismatch, dask_task, default_jobs, sweep_fingerprint
from tools.evaluate.sweep import DEFAULT_MODE, MODES, RunSpec, failed_result, run_isolated

if TYPE_CHECKING:
    from dask.typing import Key



class Executor(Protocol):
    def results(self, specs: Sequence[RunSpec], runs_dir: Path, timeout_s: float) -> Iterator[dict[str, Any]]:
        """Run every spec; yield each result as its run ends (any order)."""

    def interrupt(self) -> None:
        """Stop the runs under way (Ctrl-C): they end cleanly and are not recorded."""


class LocalExecutor:
    """``jobs`` runs at once on this machine."""

    def __init__(self, jobs: int, record: bool = True) -> None:
        self.jobs, self.record = jobs, record
        self._live: set[subprocess.Popen[bytes]] = set()
        self._stop = threading.Event()

    def results(self, specs: Sequence[RunSpec], runs_dir: Path, timeout_s: float) -> Iterator[dict[str, Any]]:
        pending = list(specs)
        with ThreadPoolExecutor(max_workers=self.jobs, thread_name_prefix="evaluate") as pool:
            running: set[Future[dict[str, Any]]] = set()
            try:
                while pending or running:
                    while pending and len(running) < self.jobs and not self._stop.is_set():
                        spec = pending.pop(0)
                        running.add(pool.submit(run_isolated, spec.to_dict(), str(runs_dir), timeout_s, self._live,
                                                record=self.record))
                    if not running:
                        return
                    done, running = wait(running, return_when=FIRST_COMPLETED)
                    for future in done:
                        yield future.result()
            except KeyboardInterrupt:
                self.interrupt()     # before the pool waits for its threads: their runs must stop
                raise

    def interrupt(self) -> None:
        self._stop.set()
        for proc in list(self._live):
            try:
                os.killpg(proc.pid, signal.SIGINT)    # the launcher stops its agents and merges
            except ProcessLookupError:
                pass


class DaskExecutor:
    """Each run a task on an existing Dask cluster (``dask://HOST:PORT``, the scheduler's address).

    A task checks the worker's chronav and scene files (tools/evaluate/pool.py dask_task), runs one
    run on its worker (in the worker process itself in-process, else a launch; under ``runs_dir``
    on that machine) and returns the run's table rows and recording path; workers need chronav
    installed, nothing shared.  Results stream back as tasks end.  A task that fails (its worker
    was lost mid-run, and the scheduler gave up on it) is submitted once more."""

    def __init__(self, address: str, mode: str = DEFAULT_MODE, record: bool = True) -> None:
        from distributed import Client

        self.address, self.mode, self.record = address, mode, record
        self.client = Client(address, timeout="20s")
        self._futures: list[Any] = []
        self.requeued: list[str] = []

    def results(self, specs: Sequence[RunSpec], runs_dir: Path, timeout_s: float) -> Iterator[dict[str, Any]]:
        from distributed import as_completed

        sweep = uuid.uuid4().hex[:8]
        fingerprints = {scene: sweep_fingerprint(scene) for scene in sorted({s.scene for s in specs})}
        by_key: dict[Key, tuple[RunSpec, int]] = {}

        def submit(spec: RunSpec, index: int, attempt: int) -> Any:
            future = self.client.submit(dask_task, spec.to_dict(), str(runs_dir), timeout_s, self.mode,
                                        fingerprints[spec.scene], self.record, pure=False,
                                        key=f"chronav-evaluate-{sweep}-{index}-{spec.slug}-a{attempt}")
            by_key[future.key] = (spec, attempt)
            self._futures.append(future)
            return future

        stream = as_completed([submit(spec, index, 1) for index, spec in enumerate(specs)])
        for index, future in enumerate(stream):
            spec, attempt = by_key[future.key]
            try:
                yield future.result()
            except WorkerMismatch as exc:
                yield failed_result(spec, str(exc))
            except Exception as exc:  # noqa: BLE001 - a worker lost or a task error: once more, then report
                if attempt == 1:
                    self.requeued.append(spec.label)
                    stream.add(submit(spec, len(specs) + index, 2))
                    continue
                yield failed_result(spec, f"the Dask task failed twice: {type(exc).__name__}: {exc}")

    def interrupt(self) -> None:
        """Queued runs are cancelled; a run already under way on a worker finishes there."""
        self.client.cancel(self._futures)

    def close(self) -> None:
        self.client.close()


def parse_executor(text: str, jobs: int | None, mode: str = DEFAULT_MODE, record: bool = True) -> Any:
    """``local`` or ``dask://HOST:PORT``; ValueError in the user's words otherwise.  ``jobs`` None:
    every core."""
    if mode not in MODES:
        raise ValueError(f"--mode {mode}: use one of {', '.join(MODES)}")
    if text == "local":
        jobs = jobs or default_jobs()
        return InProcessPool(jobs, record) if mode == "in-process" else LocalExecutor(jobs, record)
    if text.startswith("dask://"):
        address = text.removeprefix("dask://")
        host, sep, port = address.rpartition(":")
        if not sep or not host or not port.isdigit():
            raise ValueError(f"--executor {text}: expected dask://HOST:PORT, the address of a Dask scheduler")
        try:
            return DaskExecutor(f"tcp://{host}:{port}", mode, record)
        except ImportError:
            raise ValueError("--executor dask://...: Dask is not installed; install chronav's `eval` extra "
                             "(pip install 'chronav[eval]')") from None
        except (OSError, TimeoutError) as exc:
            raise ValueError(f"--executor {text}: cannot reach a Dask scheduler there ({exc}); start one "
                             "(`dask scheduler`, then `dask worker HOST:PORT` on each machine)") from None
    raise ValueError(f"--executor {text}: use local or dask://HOST:PORT")
