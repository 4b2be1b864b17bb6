"""Start, watch and restart the agent processes of one run.

Why process groups: each agent is started in its own session so that stopping it (or SIGKILL in
a fault test) also stops anything it spawned, and so that a Ctrl-C in the launcher's terminal
reaches only the launcher, which then stops the agents in order and still merges the recording.

Why a progress watch besides exit codes: an agent can hang without exiting (a loop that never
returns, a frozen process).  Each agent stamps a heartbeat in the DSR from its main loop
(agents/runtime/heartbeat.py); `ProgressWatch` turns the stamps the launcher sees into "stuck
for N s", and `Supervisor.restart_stuck` kills such an agent and starts it again (counted, and
logged, like a crash).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from tools.system.restart_budget import RestartBudget

REPO_ROOT = Path(__file__).resolve().parents[2]


@dataclass
class ManagedProcess:
    name: str
    args: list[str]
    log_path: Path
    env: dict[str, str]
    proc: subprocess.Popen[bytes] | None = None
    restarts: int = 0
    exit_codes: list[int] = field(default_factory=list)
    gave_up: bool = False
    #: why the supervisor killed the running process itself (a hang), reported when it exits
    killed_because: str | None = None

    @property
    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    @property
    def pid(self) -> int | None:
        return None if self.proc is None else self.proc.pid


class Supervisor:
    """Keeps a set of Python module processes running, restarting crashes up to ``restart_limit``
    per agent within any rolling hour of wall time (tools/system/restart_budget.py); ``budget``
    shares one such budget between supervisors (the days of a long run)."""

    def __init__(self, log_dir: Path, base_env: dict[str, str], restart_limit: int = 3,
                 budget: RestartBudget | None = None) -> None:
        self.log_dir = log_dir
        self.base_env = base_env
        self.budget = budget if budget is not None else RestartBudget(limit=restart_limit)
        self.restart_limit = self.budget.limit
        self.processes: dict[str, ManagedProcess] = {}
        self.events: list[str] = []
        self.stopping = False
        log_dir.mkdir(parents=True, exist_ok=True)

    def add(self, name: str, module: str, extra_args: list[str] | None = None,
            env: dict[str, str] | None = None) -> ManagedProcess:
        from dsr.log_rotation import LOG_FILE_ENV   # here: `chronav --help` imports this module, not the DSR

        log_path = self.log_dir / f"{name}.log"
        # The process cuts its own log in a real-time run (dsr/log_rotation.py): it must know the file.
        managed = ManagedProcess(name=name, args=["-m", module, *(extra_args or [])], log_path=log_path,
                                 env={**self.base_env, **(env or {}), LOG_FILE_ENV: str(log_path)})
        self.processes[name] = managed
        return managed

    def start(self, name: str) -> None:
        managed = self.processes[name]
        log = managed.log_path.open("ab")
        try:
            managed.proc = subprocess.Popen([sys.executable, *managed.args], cwd=REPO_ROOT, env=managed.env,
                                            stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                            start_new_session=True)
        finally:
            log.close()

    def start_all(self) -> None:
        for name in self.processes:
            self.start(name)

    def poll(self) -> list[str]:
        """Restart what died (unless stopping); return the names restarted in this call."""
        restarted: list[str] = []
        for name, managed in self.processes.items():
            if managed.proc is None or managed.gave_up or managed.proc.poll() is None or self.stopping:
                continue
            code = managed.proc.returncode
            managed.exit_codes.append(code)
            what = (f"{name} {managed.killed_because}; killed" if managed.killed_because
                    else f"{name} exited with {code}")
            reason = managed.killed_because or f"exited with {code}"
            managed.killed_because = None
            if not self.budget.allows(name):
                managed.gave_up = True
                self.events.append(f"{what}; restart limit {self.restart_limit} reached "
                                   f"({self.budget.describe()})")
                continue
            managed.restarts += 1
            used = self.budget.take(name, reason)
            self.events.append(f"{what}; restart {used}/{self.restart_limit}")
            self.start(name)
            restarted.append(name)
        return restarted

    def restart_stuck(self, name: str, reason: str) -> None:
        """Kill a process that stopped making progress (SIGKILL also ends a SIGSTOPped one);
        the next `poll` restarts it, counted against the limit, with ``reason`` in the event."""
        managed = self.processes[name]
        if managed.proc is None or managed.proc.poll() is not None or self.stopping:
            return
        managed.killed_because = reason
        self._signal(name, signal.SIGKILL)
        try:
            managed.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            pass

    def given_up(self) -> list[str]:
        return [name for name, managed in self.processes.items() if managed.gave_up]

    def kill(self, name: str, sig: int = signal.SIGKILL) -> None:
        managed = self.processes[name]
        if managed.proc is not None and managed.proc.poll() is None:
            os.killpg(managed.proc.pid, sig)

    def stop_all(self, timeout_s: float = 8.0, order: list[str] | None = None) -> None:
        """SIGTERM in ``order`` (default: reverse start order), then SIGKILL what is left."""
        self.stopping = True
        names = order or list(reversed(self.processes))
        for name in names:
            self._signal(name, signal.SIGTERM)
        deadline = time.monotonic() + timeout_s
        for name in names:
            proc = self.processes[name].proc
            if proc is None:
                continue
            try:
                proc.wait(timeout=max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                self._signal(name, signal.SIGKILL)
                proc.wait(timeout=5)

    def _signal(self, name: str, sig: int) -> None:
        proc = self.processes[name].proc
        if proc is not None and proc.poll() is None:
            try:
                os.killpg(proc.pid, sig)
            except ProcessLookupError:
                pass


@dataclass
class _Progress:
    pid: int
    since: float                 # monotonic time of the (re)start or of the last new stamp
    stamp: tuple[int, int] | None = None
    stamped: bool = False        # a stamp written by this pid was seen


class ProgressWatch:
    """Decides, from the heartbeat stamps an observer sees, which agent is stuck.

    A process gets ``startup_s`` from its (re)start to its first stamp (imports, JIT compilation,
    joining the graph), then at most ``hang_s`` between two stamps.  Stamps are (pid, beat): a
    stamp of another pid (the previous incarnation, still in the graph) is not progress."""

    def __init__(self, hang_s: float, startup_s: float) -> None:
        self.hang_s, self.startup_s = hang_s, startup_s
        self._state: dict[str, _Progress] = {}

    def observe(self, name: str, pid: int, stamp: tuple[int, int] | None, now: float) -> None:
        state = self._state.get(name)
        if state is None or state.pid != pid:
            state = self._state[name] = _Progress(pid=pid, since=now)
        if stamp is not None and stamp[0] == pid and stamp != state.stamp:
            state.stamp, state.stamped, state.since = stamp, True, now

    def overdue(self, name: str, now: float) -> str | None:
        """Why ``name`` counts as stuck now, or None."""
        state = self._state.get(name)
        if state is None:
            return None
        waited = now - state.since
        if state.stamped and waited > self.hang_s:
            return (f"made no progress for {waited:.1f} s (heartbeat {state.stamp[1] if state.stamp else '?'} "
                    f"was its last; limit {self.hang_s:g} s)")
        if not state.stamped and waited > self.startup_s:
            return f"wrote no heartbeat within {waited:.1f} s of its start (limit {self.startup_s:g} s)"
        return None
