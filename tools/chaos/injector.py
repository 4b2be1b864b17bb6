"""The fault injector of `chronav chaos`: runs a schedule against a launched system, measures.

Why a thread next to the launcher loop: `run_system` owns the main thread (its signal handlers
need it) and calls ``on_tick`` every ~0.1 s with the status (pids, endpoint, graph); blocking there
would stop the supervisor from restarting what we kill.  So ``on_tick`` only records, and faults
run on a thread of their own with a writable replica named ``agenda_tool-chaos`` (the write
policy's agenda tools may ask for agenda changes; it writes nothing but ``agenda_request`` nodes).
"""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from tools.chaos.checks import describe_divergence, probe_replicas
from tools.chaos.schedule import Fault, clock_text
from tools.launch import agent_names

CHAOS_AGENT = "agenda_tool-chaos"
PROBE_PERIOD_S = 0.2


@dataclass
class FaultOutcome:
    fault: Fault
    injected: bool = False
    at_wall_s: float | None = None        # since the first mission started
    at_sim_s: float | None = None         # sim clock at injection (s since midnight)
    mission: str | None = None            # mission active at injection
    recovered_s: float | None = None      # until the target answered again / request answered
    converged_s: float | None = None      # until every live replica had the same digest
    note: str = ""

    def as_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out["fault"] = {k: v for k, v in asdict(self.fault).items() if v not in (None, 0.0, False)}
        out["what"] = self.fault.describe()
        return out


class ChaosRun:
    """Fault injection and observation around one `run_system` call.

    ``on_tick`` runs on the launcher's thread (it only records the status and, at the end, takes
    the final digest sample); faults run on a thread of their own with a writable replica named
    ``agenda_tool-chaos`` that writes nothing but ``agenda_request`` nodes."""

    def __init__(self, schedule: list[Fault], *, converge_timeout_s: float = 30.0,
                 log: Callable[[str], None] | None = None) -> None:
        self.schedule = schedule
        self.converge_timeout_s = converge_timeout_s
        self.outcomes = [FaultOutcome(f) for f in schedule]
        self.log = log or (lambda _text: None)
        self.status: dict[str, Any] = {}
        self.activated: dict[str, float] = {}     # mission -> monotonic time first seen active
        self.done_seen: set[str] = set()
        self.final_converged = False
        self.graph: Any = None                    # the chaos replica's DSRGraph
        self._replica: Any = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._stopped_pids: set[int] = set()
        self._final_probed = False
        self._requests: list[str] = []
        self.final_divergence = ""
        self._last_copies: dict[str, Any] = {}
        self._unsettled: tuple[FaultOutcome, float] | None = None
        #: refusals, fetches, unproven claims and ACL denials at the end (tools/chaos/checks.py)
        self.trust: dict[str, Any] = {}

    # --------------------------------------------------------------- launcher thread
    def on_tick(self, status: dict[str, Any]) -> None:
        from agents.world.vocabulary import MissionState
        self.status = status
        now = time.monotonic()
        missions = status.get("missions", {})
        for mission_id, attrs in missions.items():
            if attrs.get("state") in (MissionState.ACTIVE, *MissionState.TERMINAL):
                self.activated.setdefault(mission_id, now)
            if attrs.get("state") == MissionState.DONE:
                self.done_seen.add(mission_id)
        if self._thread is None and "run" in status:
            self._thread = threading.Thread(target=self._main, name="chaos-injector", daemon=True)
            self._thread.start()
        if missions and all(m.get("state") in MissionState.TERMINAL for m in missions.values()) \
                and not self._final_probed:
            self._final_probed = True
            self.finish()
            final = self._converge(timeout_s=10.0, final=True)
            self.final_converged = final is not None
            self.final_divergence = "" if self.final_converged else self._divergence()
            self.trust = self._trust()
            if self._unsettled is not None and final is not None:
                outcome, t0 = self._unsettled
                outcome.converged_s = round(time.monotonic() - t0, 3)
                outcome.note = (outcome.note + " " if outcome.note else "") + "converged after the last mission"

    def finish(self) -> None:
        """Stop injecting (resumes anything still stopped) and wait for the injector."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=30)
        self._resume_all()

    def close(self) -> None:
        """Stop injecting, close the chaos replica, then wait for the injector thread again:
        closing the session ends any Zenoh call it is still blocked in (a probe, a state
        fetch), and it must not be inside one when the process ends (agents/runtime/exit_guard.py)."""
        self.finish()
        if self._replica is not None:
            self._replica.close()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=10)

    # --------------------------------------------------------------- injector thread
    def _main(self) -> None:
        from dsr import DSRGraph
        from dsr.transport import Replica
        from tools.system.connection import Target, settings_for
        from tools.system.runs import read_connect_file

        run = self.status["run"]
        info = read_connect_file(Path(run["run_dir"]))   # the run's tool identity: writes as agenda_tool-*
        settings = settings_for(Target((info.endpoint,), info.graph, f"run {info.run_id}", info.run_dir,
                                       info.identity("tool")))
        self.graph = DSRGraph(CHAOS_AGENT, graph=run["graph"])
        self._replica = Replica(self.graph, settings)
        try:
            self._replica.open()
            for outcome in self.outcomes:
                if not self._wait_trigger(outcome.fault):
                    break
                self._inject(outcome)
        except Exception as exc:  # noqa: BLE001 - report it; the run itself goes on
            self.log(f"chaos injector stopped: {type(exc).__name__}: {exc}")
        finally:
            self._resume_all()

    def _sleep(self, seconds: float) -> bool:
        """False when the run is over."""
        return not self._stop.wait(max(0.0, seconds))

    def _wait_trigger(self, fault: Fault) -> bool:
        from agents.world.vocabulary import NodeType
        driving_since: float | None = None
        while not self._stop.is_set():
            now = time.monotonic()
            started = self.activated.get(fault.mission) if fault.mission else min(self.activated.values(), default=None)
            if fault.driving and started is not None:
                driving = any(n.attrs.get("nav_active") for n in self.graph.nodes_of_type(NodeType.ROBOT))
                driving_since = (driving_since or now) if driving else None
                started = driving_since
            if started is not None and now >= started + fault.at_s:
                return True
            self._sleep(0.05)
        return False

    def _pid(self, name: str) -> int | None:
        return self.status.get("pids", {}).get(name)

    def _signal(self, pid: int, sig: int) -> None:
        try:
            os.killpg(pid, sig)
        except ProcessLookupError:
            pass

    def _resume_all(self) -> None:
        for pid in list(self._stopped_pids):
            self._signal(pid, signal.SIGCONT)
            self._stopped_pids.discard(pid)

    def _inject(self, outcome: FaultOutcome) -> None:
        from agents.world.vocabulary import MissionState
        fault = outcome.fault
        first = min(self.activated.values(), default=time.monotonic())
        clock = self.graph.get_node_by_name("clock")
        active = [m for m, a in self.status.get("missions", {}).items() if a.get("state") == MissionState.ACTIVE]
        outcome.at_wall_s = round(time.monotonic() - first, 2)
        outcome.at_sim_s = None if clock is None else round(float(clock.attrs.get("now_s", 0.0)), 2)
        outcome.mission = active[0] if active else None
        self.log(f"fault: {fault.describe()} (mission {outcome.mission}, sim {clock_text(outcome.at_sim_s)})")
        if fault.action == "agenda":
            name = self._request(fault.change or "")
            outcome.injected = True
            t0 = time.monotonic()
            if self._wait(lambda: self._request_state(name) in ("accepted", "refused"), 20.0):
                outcome.recovered_s = round(time.monotonic() - t0, 3)
                outcome.note = str(self._request_state(name))
            else:
                outcome.note = "request not answered in 20 s"
        else:
            pid = self._pid(fault.target)
            if pid is None:
                outcome.note = f"no pid for {fault.target}"
                return
            if fault.action == "kill":
                self._signal(pid, signal.SIGKILL)
                outcome.injected = True
                t0 = time.monotonic()
                restarted = self._wait(lambda: self._pid(fault.target) not in (None, pid), 20.0)
                if not restarted:
                    outcome.note = "not restarted in 20 s"
                    return
            else:
                self._signal(pid, signal.SIGSTOP)
                self._stopped_pids.add(pid)
                outcome.injected = True
                self._sleep(fault.hold_s)
                self._signal(pid, signal.SIGCONT)
                self._stopped_pids.discard(pid)
                t0 = time.monotonic()
            back = {fault.target} if fault.target != "router" else self._expected()
            answered = self._wait(lambda: back <= set(self._safe_probe()), 30.0)
            outcome.recovered_s = round(time.monotonic() - t0, 3) if answered else None
        converged = self._converge(self.converge_timeout_s, since=t0)
        outcome.converged_s = None if converged is None else round(converged, 3)
        if converged is None and self._stop.is_set():
            self._unsettled = (outcome, t0)  # the missions ended first: the final sample decides
        elif converged is None:
            outcome.note = (outcome.note + " " if outcome.note else "") + f"diverged: {self._divergence()}"

    def _wait(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if predicate():
                return True
            if not self._sleep(0.05):
                return predicate()
        return predicate()

    def _request(self, change: str) -> str:
        from agents.world.vocabulary import NodeType, RequestState
        index = len(self._requests)
        name = f"agenda_request/chaos-{os.getpid()}-{index}"
        self.graph.insert_node(type=NodeType.AGENDA_REQUEST, name=name,
                               attrs={"change": change, "state": RequestState.PENDING, "requested_by": CHAOS_AGENT})
        self._requests.append(name)
        return name

    def _request_state(self, name: str) -> str | None:
        node = self.graph.get_node_by_name(name)
        return None if node is None else str(node.attrs.get("state"))

    def _safe_probe(self) -> dict[str, str]:
        """Digests by agent ({} while this replica is cut off); keeps the copies for diagnosis."""
        session = None if self._replica is None else self._replica.session
        if session is None:
            return {}
        try:
            copies = probe_replicas(session, self.graph.graph_name)
        except Exception as exc:  # noqa: BLE001 - a replica mid-restart may answer garbage
            self.log(f"probe failed: {type(exc).__name__}: {exc}")
            return {}
        self._last_copies = copies
        return {agent: copy.digest() for agent, copy in copies.items()}

    def _trust(self) -> dict[str, Any]:
        """The trust counters at the end of the run (tools/chaos/checks.py trust_summary)."""
        from tools.chaos.checks import trust_summary
        from tools.system.connection import graph_stats
        session = None if self._replica is None else self._replica.session
        if session is None:
            return {}
        try:
            return trust_summary(graph_stats(session, self.graph.graph_name, 2.0), self._last_copies)
        except Exception as exc:  # noqa: BLE001 - a report, not a reason to fail the run
            self.log(f"trust counters unavailable: {type(exc).__name__}: {exc}")
            return {}

    def _divergence(self) -> str:
        """How the last sample failed: missing answers, or who differs on what."""
        missing = self._expected() - set(self._last_copies)
        return describe_divergence(self._last_copies) or (
            f"no answer from {', '.join(sorted(missing))}" if missing else "")

    def _expected(self) -> set[str]:
        """Replicas that must answer: every agent and this one (read-only ones, like the
        launcher's, serve no state; any other writable replica that answers must agree too)."""
        return {*agent_names(), CHAOS_AGENT}

    def _converge(self, timeout_s: float, since: float | None = None, final: bool = False) -> float | None:
        """Seconds from ``since`` until one sample where all expected replicas agree, or None.

        The injector's probes give up when the run ends; the ``final`` one is taken then."""
        since = time.monotonic() if since is None else since
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and (final or not self._stop.is_set()):
            digests = self._safe_probe()
            if self._expected() <= set(digests) and len(set(digests.values())) == 1:
                return time.monotonic() - since
            time.sleep(PROBE_PERIOD_S)
        return None

    # --------------------------------------------------------------- after the run
    def request_states(self) -> dict[str, str]:
        return {name: str(self._request_state(name)) for name in self._requests}
