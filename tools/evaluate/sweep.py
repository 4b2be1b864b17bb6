"""A sweep: every scene x planner x seed as one isolated run of the whole system, locally or on Dask.

Two modes run the same agents (``--mode``):

- ``in-process`` (the default): the six agents in one process, stepped in lockstep on one graph
  (tools/inprocess.py).  Runs go to a pool of worker processes (``--jobs``, all cores by default)
  that each keep their imports and compiled numba kernels from one run to the next; on Dask, a
  task runs in the worker itself.  A run of the tiny scene then takes a fraction of a second.
- ``launch``: each run a full ``chronav launch`` (router on a free port, the run's own credentials
  and run directory, six agents as processes; tools/launch.run_system), the reference the
  in-process mode is checked against (tests/system/test_parity.py).  The launcher installs signal
  handlers, which Python allows only in a main thread, and the pools run tasks in threads, so each
  task starts one ``python -m tools.evaluate.sweep`` process and waits for it.

The planner is the navigation agent's ``-o planner=NAME`` (agents/lib/planning/planners.py).  The
seed goes to every agent as ``-o seed=N``: each agent that draws random numbers (today the human
observer's sensor noise; the people simulation of issue 15 next) seeds its generator with it, so
one seed is one simulated world.  The simulator gets ``-o busy_rate=0``: its clock waits while the
executive and the navigation plan instead of running on in real time, and ``watchdog_s=30``: a
command that comes late (a slow replan on a loaded machine) is waited for instead of braking after
one wall second; the simulator and the navigation get ``perception_lockstep=1``: the clock moves
on only once the perceivers processed the tick, and the navigation answers a pose only then, so
the observer detects people at every tick, in a launch as in-process.  Sim times (when the robot
leaves, what R and the people are then) and the driven path then do not depend on how loaded the
machine is.

Finished runs are appended to ``DIR/runs.jsonl`` as they end (one JSON object per run with its
table rows); ``--resume`` skips the runs found there, so an interrupted sweep continues where it
stopped.  A run counts as finished unless it was interrupted or could not run at all (its
missions may still have failed: that is a result).
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
import uuid
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

LEDGER = "runs.jsonl"
MODES = ("in-process", "launch")
DEFAULT_MODE = "in-process"
WORKER_LOGS = "worker-logs"
#: wall seconds the simulator waits for a late velocity command before braking (default 1 s)
LOCKSTEP_WATCHDOG_S = 30.0
#: wall seconds a run may take beyond its --timeout (stopping agents, merging the recording)
CLEANUP_GRACE_S = 180.0


#: the local controller of a run that names none (agents/lib/control/controllers.py); its runs keep
#: the keys, labels and report names they had before controllers were an axis
DEFAULT_CONTROLLER = "elastic_band"


def method_label(planner: str, controller: str) -> str:
    """The report's name of a planner x controller pair: the planner alone with the default controller."""
    return planner if controller == DEFAULT_CONTROLLER else f"{planner}+{controller}"


@dataclass(frozen=True, order=True)
class RunSpec:
    """One run of a sweep: a scene file, a planner, a seed and a local controller."""

    scene: str     # absolute path of the scene file
    planner: str
    seed: int
    controller: str = DEFAULT_CONTROLLER
    model: str = ""   # the observer's walker model file (evaluate --model); "" the shipped one

    @property
    def method(self) -> str:
        return method_label(self.planner, self.controller)

    @property
    def key(self) -> str:
        extra = "" if self.controller == DEFAULT_CONTROLLER else f"|{self.controller}"
        return f"{self.scene}|{self.planner}|{self.seed}{extra}" + (f"|{self.model}" if self.model else "")

    @property
    def label(self) -> str:
        return f"{Path(self.scene).stem}/{self.method}/seed {self.seed}"

    @property
    def slug(self) -> str:
        return f"{Path(self.scene).stem}-{self.method}-s{self.seed}"

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> RunSpec:
        return cls(str(data["scene"]), str(data["planner"]), int(data["seed"]),
                   str(data.get("controller", DEFAULT_CONTROLLER)), str(data.get("model") or ""))


def plan_sweep(scenes: Sequence[Path], planners: Sequence[str], seeds: Sequence[int],
               controllers: Sequence[str] = (DEFAULT_CONTROLLER,), model: str = "") -> list[RunSpec]:
    """Every combination, seed by seed: a sweep stopped half way already holds whole seeds."""
    return [RunSpec(str(scene), planner, seed, controller, model) for seed in seeds for scene in scenes
            for planner in planners for controller in controllers]


def agent_options(spec: RunSpec) -> dict[str, list[str]]:
    """``-o`` options of each agent for one run: the seed for all, the planner for the navigation."""
    from tools.inprocess import lockstep_options
    from tools.launch import agent_names

    lockstep = lockstep_options()
    options = {name: [f"seed={spec.seed}", *lockstep.get(name, [])] for name in agent_names()}
    options["social_navigation"] += [f"planner={spec.planner}", f"controller={spec.controller}"]
    if spec.model:
        options["human_observer"].append(f"walker_model={spec.model}")
    # Lockstep without wall-clock escapes: sim time waits while the agents plan and perceive, and a
    # late command (a slow replan on a loaded machine) is waited for instead of braking after 1 wall s.
    options["sim_robot"] += [f"watchdog_s={LOCKSTEP_WATCHDOG_S}"]
    return options


# ---------------------------------------------------------------------------------------------
# One run (inside its own process).
# ---------------------------------------------------------------------------------------------

def execute_run(spec: RunSpec, runs_dir: Path, timeout_s: float, mode: str = "launch",
                stop: threading.Event | None = None, record: bool = True) -> dict[str, Any]:
    """Run the system for ``spec`` (headless; recorded unless ``record`` is False) in ``mode`` and
    measure its missions."""
    from tools.system.console import outcome
    from tools.evaluate.table import mission_rows

    if mode == "in-process":
        from tools.inprocess import run_in_process

        result = run_in_process(spec.scene, runs_dir=runs_dir, timeout_s=timeout_s, record=record,
                                agent_options=agent_options(spec), stop=stop)
    else:
        from tools.launch import run_system

        result = run_system(spec.scene, runs_dir=runs_dir, timeout_s=timeout_s, record=record,
                            agent_options=agent_options(spec), metrics_report=False)
    rrd = str(result.rrd_path) if result.rrd_path else None
    host = socket.gethostname()
    (result.run_dir / "evaluate.json").write_text(json.dumps({**spec.to_dict(), "host": host}))
    rows = [] if result.interrupted else mission_rows(
        scene=spec.scene, planner=spec.planner, controller=spec.controller, seed=spec.seed, run_dir=result.run_dir, rrd=rrd,
        missions=result.missions, host=host, run_wall_s=result.wall_s)
    return {"key": spec.key, "spec": spec.to_dict(), "ok": result.ok, "outcome": outcome(result),
            "error": result.error, "interrupted": result.interrupted, "run_dir": str(result.run_dir), "rrd": rrd,
            "host": host, "wall_s": result.wall_s, "mode": mode, "rows": rows}


def failed_result(spec: RunSpec, message: str, *, interrupted: bool = False) -> dict[str, Any]:
    """The result of a run that could not run (or was cut short): no rows, not finished."""
    return {"key": spec.key, "spec": spec.to_dict(), "ok": False, "outcome": "interrupted" if interrupted else "error",
            "error": message, "interrupted": interrupted, "run_dir": None, "rrd": None,
            "host": socket.gethostname(), "wall_s": 0.0, "rows": []}


def finished(result: dict[str, Any]) -> bool:
    """A run that counts (its missions may have failed), as opposed to one to run again."""
    return not result.get("interrupted") and result.get("error") is None and result.get("run_dir") is not None


def run_isolated(spec_data: dict[str, Any], runs_dir: str, timeout_s: float,
                 live: set[subprocess.Popen[bytes]] | None = None, record: bool = True) -> dict[str, Any]:
    """One run in its own process (its own session), waited for; the task body of every executor.

    ``live`` (local executor) collects the running processes so that Ctrl-C can be passed on."""
    spec = RunSpec.from_dict(spec_data)
    logs = Path(runs_dir) / WORKER_LOGS
    logs.mkdir(parents=True, exist_ok=True)
    stem = f"{spec.slug}-{uuid.uuid4().hex[:8]}"
    result_file, log_file = logs / f"{stem}.json", logs / f"{stem}.log"
    args = [sys.executable, "-m", "tools.evaluate.sweep", "--spec", json.dumps(spec.to_dict()),
            "--runs-dir", str(runs_dir), "--timeout", str(timeout_s), "--result", str(result_file),
            *([] if record else ["--no-record"])]
    with log_file.open("wb") as log:
        # Recorded (RERUN=on whatever the worker's environment says: the report links each run),
        # unless the sweep said --no-record.
        proc = subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT, start_new_session=True,
                                env={**os.environ, "RERUN": "on" if record else "off"})
        if live is not None:
            live.add(proc)
        try:
            proc.wait(timeout=timeout_s + CLEANUP_GRACE_S)
        except subprocess.TimeoutExpired:
            _kill_group(proc)
            return failed_result(spec, f"the run did not end within {timeout_s + CLEANUP_GRACE_S:.0f} s; "
                                       f"log: {log_file}")
        finally:
            if live is not None:
                live.discard(proc)
    try:
        return json.loads(result_file.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        lines = log_file.read_text(encoding="utf-8", errors="replace").strip().splitlines()
        last = lines[-1] if lines else "no output"
        return failed_result(spec, f"the run's process ended (exit {proc.returncode}) without a result: {last} "
                                   f"(log: {log_file})", interrupted=proc.returncode in (130, -2))


def _kill_group(proc: subprocess.Popen[bytes]) -> None:
    try:
        os.killpg(proc.pid, signal.SIGTERM)
        proc.wait(timeout=60)
    except (ProcessLookupError, subprocess.TimeoutExpired):
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait()


# ---------------------------------------------------------------------------------------------
# The ledger of finished runs (resume).
# ---------------------------------------------------------------------------------------------

def read_ledger(out_dir: Path) -> dict[str, dict[str, Any]]:
    """Finished runs recorded under ``out_dir`` by key (a torn last line is ignored)."""
    path = out_dir / LEDGER
    found: dict[str, dict[str, Any]] = {}
    if not path.exists():
        return found
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            result = json.loads(line)
        except ValueError:
            continue
        if isinstance(result, dict) and finished(result):
            found[str(result["key"])] = result
    return found


def append_ledger(out_dir: Path, result: dict[str, Any]) -> None:
    with (out_dir / LEDGER).open("a", encoding="utf-8") as handle:
        handle.write(json.dumps(result) + "\n")
        handle.flush()
        os.fsync(handle.fileno())


def main(argv: list[str] | None = None) -> int:
    """``python -m tools.evaluate.sweep --spec JSON ...``: one run, its result as a JSON file."""
    parser = argparse.ArgumentParser(prog="python -m tools.evaluate.sweep")
    parser.add_argument("--spec", required=True)
    parser.add_argument("--runs-dir", required=True, type=Path)
    parser.add_argument("--timeout", required=True, type=float)
    parser.add_argument("--result", required=True, type=Path)
    parser.add_argument("--no-record", action="store_true")
    args = parser.parse_args(argv)
    spec = RunSpec.from_dict(json.loads(args.spec))
    started = time.monotonic()
    result = execute_run(spec, args.runs_dir, args.timeout, record=not args.no_record)
    result["task_wall_s"] = time.monotonic() - started
    tmp = args.result.with_suffix(".tmp")
    tmp.write_text(json.dumps(result))
    tmp.replace(args.result)
    return 130 if result["interrupted"] else 0


if __name__ == "__main__":
    sys.exit(main())
