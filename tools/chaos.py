"""`chronav chaos SCENE`: run the whole system under a fault schedule and report what survived.

A fault is a SIGKILL of an agent or of the Zenoh router (the launcher restarts it), a SIGSTOP
followed by SIGCONT (a frozen process: longer than the 2 s link lease it is declared gone and
must rejoin), or an agenda change injected through the DSR ``agenda_request`` protocol of
agents/agenda/agent.py.  Faults run one at a time, while missions are under way, and after each
one the tool measures:

- **recovery**: until the faulted process answers again (its replica rejoined the graph);
- **convergence**: until every live replica reports the same graph digest.  Replicas are asked
  for their full CRDT state in ONE Zenoh query (``chronav/<graph>/state/*``), each answer is
  loaded into an offline :class:`dsr.DSRGraph` and hashed with ``digest()``; the system never
  stops writing (the clock ticks), so this is a sampled measure: the first sample where all
  digests agree.

"Writes lost" must be 0: every mission seen ``done`` is still done at the end, every agenda change
answered ``accepted`` is in the agenda's change log exactly once, and the activities the agenda
agent publishes are exactly the scene's agenda with that log replayed (what a restarted agenda
agent rebuilds).  The run itself is `tools.launch.run_system`, unchanged: faults are injected
from a thread fed by its ``on_tick`` status (pids, endpoint, graph).
"""

from __future__ import annotations

import json
import os
import random
import signal
import threading
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Literal

import typer

from tools.launch import AGENTS, TERMINAL_STATES

PROCESSES: tuple[str, ...] = (*AGENTS, "router")
# Matches the write policy's "agenda_tool-*" writers (deploy/write_policy.yaml): may ask for agenda changes.
CHAOS_AGENT = "agenda_tool-chaos"
ACTIONS: tuple[str, ...] = ("kill", "stop", "agenda")
Action = Literal["kill", "stop", "agenda"]
PROBE_PERIOD_S = 0.2


class ChaosError(Exception):
    """The chaos run could not be set up (bad schedule, scene, ...); the message says why."""


# ----------------------------------------------------------------------------- schedule
@dataclass(frozen=True)
class Fault:
    """One fault. Trigger: ``at_s`` wall seconds after ``mission`` became active (or, without a
    mission, after the first mission became active); with ``driving``, ``at_s`` seconds into a
    stretch of the robot driving (``nav_active``) once the mission is active.  Never before the
    previous fault converged."""

    action: Action
    target: str
    at_s: float = 0.0
    mission: str | None = None
    hold_s: float = 0.0
    change: str | None = None     # agenda change JSON (agents/agenda/changes.py wire form)
    driving: bool = False

    def __post_init__(self) -> None:
        if self.action not in ACTIONS:
            raise ChaosError(f"fault action must be one of {', '.join(ACTIONS)}, not {self.action!r}")
        if self.action in ("kill", "stop") and self.target not in PROCESSES:
            raise ChaosError(f"fault target must be one of {', '.join(PROCESSES)}, not {self.target!r}")
        if self.action == "agenda" and not self.change:
            raise ChaosError("an agenda fault needs a change (JSON of an add/cancel/move change)")
        if self.at_s < 0 or self.hold_s < 0:
            raise ChaosError(f"fault times must not be negative ({self.at_s}, {self.hold_s})")

    def describe(self) -> str:
        if self.action == "agenda":
            return f"agenda {json.loads(self.change or '{}').get('op', '?')}"
        return f"{self.action} {self.target}" + (f" {self.hold_s:.1f}s" if self.action == "stop" else "")


def _hhmm(seconds: float) -> str:
    minutes = int(seconds // 60)
    return f"{minutes // 60:02d}:{minutes % 60:02d}"


def _clock(seconds: float | None) -> str:
    if seconds is None:
        return "-"
    from scenes.model import format_clock

    return format_clock(seconds)


def random_agenda_change(rng: random.Random, scene: Any, known_ids: list[str], index: int, tag: str) -> str:
    """A plausible staff edit: add an activity on a scene object, move or cancel a known one."""
    from scenes.model import parse_clock

    start_min = int(parse_clock(scene.clock.start) // 60)
    end_min = int(parse_clock(scene.clock.end) // 60)
    op = rng.choice(("add", "add", "move", "cancel")) if known_ids else "add"
    if op == "add" or not scene.objects:
        begin = rng.randrange(start_min, max(start_min + 1, end_min - 15))
        length = rng.choice((15, 30, 45, 60))
        activity_id = f"{tag}_{index}"
        known_ids.append(activity_id)
        return json.dumps({"op": "add", "activity": {
            "id": activity_id, "name": f"chaos activity {index}", "object": rng.choice(scene.objects).name,
            "start": _hhmm(begin * 60), "end": _hhmm(min(begin + length, 24 * 60 - 1) * 60)}})
    target = rng.choice(known_ids)
    if op == "cancel":
        return json.dumps({"op": "cancel", "id": target})
    begin = rng.randrange(start_min, max(start_min + 1, end_min - 15))
    return json.dumps({"op": "move", "id": target, "start": _hhmm(begin * 60)})


def random_schedule(loaded: Any, *, seed: int, faults: int, duration_s: float) -> list[Fault]:
    """``faults`` faults at random wall times within ``duration_s`` after the first mission starts.

    Deterministic for a seed.  Kills and stops pick any agent or the router; stops last 0.3-3 s
    (either side of the 2 s link lease); agenda edits add, move or cancel activities."""
    if faults < 0 or duration_s <= 0:
        raise ChaosError(f"need faults >= 0 and duration > 0 (got {faults}, {duration_s})")
    rng = random.Random(seed)
    known_ids = list(loaded.agenda_day.ids())
    out: list[Fault] = []
    for index, at_s in enumerate(sorted(rng.uniform(0.0, duration_s) for _ in range(faults))):
        action = rng.choices(ACTIONS, weights=(4, 3, 3))[0]
        if action == "agenda":
            change = random_agenda_change(rng, loaded.scene, known_ids, index, f"chaos{seed}")
            out.append(Fault("agenda", "agenda", at_s=round(at_s, 2), change=change))
        else:
            hold = round(rng.uniform(0.3, 3.0), 2) if action == "stop" else 0.0
            out.append(Fault(action, rng.choice(PROCESSES), at_s=round(at_s, 2), hold_s=hold))
    return out


def load_schedule(path: Path) -> list[Fault]:
    """A schedule file: a JSON list of faults (the "fault" objects of a chaos summary replay a run).

    ``change`` may be given as an object; errors name the file and the fault's index."""
    try:
        items = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ChaosError(f"{path}: cannot read a JSON schedule: {exc}") from None
    if not isinstance(items, list):
        raise ChaosError(f"{path}: a schedule is a JSON list of faults")
    faults: list[Fault] = []
    for index, item in enumerate(items):
        try:
            if not isinstance(item, dict):
                raise TypeError("a fault is an object such as {\"action\": \"kill\", \"target\": \"router\"}")
            if isinstance(item.get("change"), dict):
                item = {**item, "change": json.dumps(item["change"])}
            faults.append(Fault(**item))
        except (TypeError, ChaosError) as exc:
            raise ChaosError(f"{path}: fault {index}: {exc}") from None
    return faults


# ----------------------------------------------------------------------------- probing replicas
def probe_replicas(session: Any, graph_name: str, timeout_s: float = 2.0) -> dict[str, Any]:
    """Every replica that answers one state query, as an offline DSRGraph copy, by agent name."""
    import zenoh

    from dsr import DSRGraph, wire

    copies: dict[str, Any] = {}
    replies = session.get(wire.state_key(graph_name, "*"), target=zenoh.QueryTarget.ALL,
                          consolidation=zenoh.ConsolidationMode.NONE, timeout=timeout_s)
    for reply in replies:
        if reply.ok is None:
            continue
        message = wire.decode(reply.ok.payload.to_bytes())
        copy = DSRGraph("probe", graph=graph_name)
        copy.apply_message(message)
        copies[message.agent] = copy
    return copies


def describe_divergence(copies: dict[str, Any], limit: int = 4) -> str:
    """Which replicas disagree with the largest group, and on which nodes/edges (for the report)."""
    groups: dict[str, list[str]] = {}
    for agent, copy in copies.items():
        groups.setdefault(copy.digest(), []).append(agent)
    if len(groups) <= 1:
        return ""
    majority = max(groups.values(), key=len)

    def elements(copy: Any) -> dict[str, Any]:
        document = copy.to_document()
        names = {n["id"]: n["name"] for n in document["nodes"]}
        out = {f"node {n['name']}": (n["type"], n["attrs"]) for n in document["nodes"]}
        out |= {f"edge {names.get(e['src'])}-{e['type']}->{names.get(e['dst'])}": e["attrs"] for e in document["edges"]}
        return out

    reference = elements(copies[majority[0]])
    parts = []
    for agents in groups.values():
        if agents is majority:
            continue
        other = elements(copies[agents[0]])
        differ = sorted(k for k in reference.keys() | other.keys() if reference.get(k) != other.get(k))
        parts.append(f"{','.join(sorted(agents))} vs {','.join(sorted(majority))}: "
                     f"{'; '.join(differ[:limit])}{' ...' if len(differ) > limit else ''}")
    return " | ".join(parts)


# ----------------------------------------------------------------------------- outcomes
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


@dataclass
class ChaosReport:
    scene: str
    ok: bool
    faults: list[FaultOutcome]
    missions: dict[str, str]
    writes_lost: int
    lost: list[str]
    requests: dict[str, str]
    final_converged: bool
    final_divergence: str
    restarts: dict[str, int]
    wall_s: float
    run_dir: str
    rrd: str | None
    events: list[str] = field(default_factory=list)

    def summary(self) -> dict[str, Any]:
        """The one JSON object of `chronav chaos --json`."""
        injected = [f for f in self.faults if f.injected]
        times = [f.converged_s for f in injected if f.converged_s is not None]
        return {
            "scene": self.scene, "ok": self.ok,
            "faults_planned": len(self.faults), "faults_injected": len(injected),
            "faults_by_action": {a: sum(1 for f in injected if f.fault.action == a) for a in ACTIONS},
            "missions_total": len(self.missions),
            "missions_completed": sum(1 for s in self.missions.values() if s == "done"),
            "missions": self.missions,
            "convergence_max_s": max(times) if times else None,
            "convergence_mean_s": sum(times) / len(times) if times else None,
            "not_converged": sum(1 for f in injected if f.converged_s is None),
            "final_converged": self.final_converged, "final_divergence": self.final_divergence,
            "writes_lost": self.writes_lost, "lost": self.lost,
            "agenda_requests": self.requests, "restarts": self.restarts,
            "wall_s": round(self.wall_s, 2), "run_dir": self.run_dir, "rrd": self.rrd,
            "faults": [f.as_dict() for f in self.faults], "events": self.events,
        }


# ----------------------------------------------------------------------------- the injector
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

    # --------------------------------------------------------------- launcher thread
    def on_tick(self, status: dict[str, Any]) -> None:
        self.status = status
        now = time.monotonic()
        missions = status.get("missions", {})
        for mission_id, attrs in missions.items():
            if attrs.get("state") in ("active", *TERMINAL_STATES):
                self.activated.setdefault(mission_id, now)
            if attrs.get("state") == "done":
                self.done_seen.add(mission_id)
        if self._thread is None and "run" in status:
            self._thread = threading.Thread(target=self._main, name="chaos-injector", daemon=True)
            self._thread.start()
        if missions and all(m.get("state") in TERMINAL_STATES for m in missions.values()) \
                and not self._final_probed:
            self._final_probed = True
            self.finish()
            final = self._converge(timeout_s=10.0, final=True)
            self.final_converged = final is not None
            self.final_divergence = "" if self.final_converged else self._divergence()
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
        self.finish()
        if self._replica is not None:
            self._replica.close()

    # --------------------------------------------------------------- injector thread
    def _main(self) -> None:
        from dsr import DSRGraph
        from dsr.config import ZenohSettings
        from dsr.transport import Replica

        run = self.status["run"]
        settings = ZenohSettings.from_env({"CHRONAV_ZENOH_CONNECT": run["endpoint"], "CHRONAV_ZENOH_MODE": "client"})
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
        driving_since: float | None = None
        while not self._stop.is_set():
            now = time.monotonic()
            started = self.activated.get(fault.mission) if fault.mission else min(self.activated.values(), default=None)
            if fault.driving and started is not None:
                driving = any(n.attrs.get("nav_active") for n in self.graph.nodes_of_type("robot"))
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
        fault = outcome.fault
        first = min(self.activated.values(), default=time.monotonic())
        clock = self.graph.get_node_by_name("clock")
        active = [m for m, a in self.status.get("missions", {}).items() if a.get("state") == "active"]
        outcome.at_wall_s = round(time.monotonic() - first, 2)
        outcome.at_sim_s = None if clock is None else round(float(clock.attrs.get("now_s", 0.0)), 2)
        outcome.mission = active[0] if active else None
        self.log(f"fault: {fault.describe()} (mission {outcome.mission}, sim {_clock(outcome.at_sim_s)})")
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
        index = len(self._requests)
        name = f"agenda_request/chaos-{os.getpid()}-{index}"
        self.graph.insert_node(type="agenda_request", name=name,
                               attrs={"change": change, "state": "pending", "requested_by": CHAOS_AGENT})
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

    def _divergence(self) -> str:
        """How the last sample failed: missing answers, or who differs on what."""
        missing = self._expected() - set(self._last_copies)
        return describe_divergence(self._last_copies) or (
            f"no answer from {', '.join(sorted(missing))}" if missing else "")

    def _expected(self) -> set[str]:
        """Replicas that must answer: every agent and this one (read-only ones, like the
        launcher's, serve no state; any other writable replica that answers must agree too)."""
        return {*AGENTS, CHAOS_AGENT}

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


def lost_writes(graph: Any, loaded: Any, done_seen: set[str], accepted: list[str]) -> list[str]:
    """Every acknowledged write that is not in the final graph, as a sentence each (empty: none).

    ``accepted``: change JSON texts whose requests were answered "accepted"."""
    from agents.agenda.changes import AgendaChangeError, apply_change, parse_change

    lost: list[str] = []
    for node in graph.nodes_of_type("mission"):
        mission_id = str(node.attrs.get("mission_id", node.name))
        if mission_id in done_seen and node.attrs.get("state") != "done":
            lost.append(f"mission {mission_id} was done, now {node.attrs.get('state')!r}")
    missing = done_seen - {str(n.attrs.get("mission_id", n.name)) for n in graph.nodes_of_type("mission")}
    lost += [f"mission {m} was done, now missing" for m in sorted(missing)]
    agenda = graph.get_node_by_name("agenda")
    log = list(agenda.attrs.get("changes", [])) if agenda is not None else []
    for text in accepted:
        count = log.count(text)
        if count != 1:
            lost.append(f"accepted agenda change {text} is {count} times in the agenda's change log")
    scene = loaded.scene
    day = loaded.agenda_day
    for text in log:
        try:
            day = apply_change(day, parse_change(text), known_objects={o.name for o in scene.objects},
                               known_rooms={r.name for r in scene.rooms})
        except AgendaChangeError as exc:
            lost.append(f"logged agenda change {text} no longer applies: {exc}")
    published = {str(n.attrs.get("activity_id")): n.attrs for n in graph.nodes_of_type("activity")}
    for activity in day.activities:
        attrs = published.get(activity.id)
        if attrs is None:
            lost.append(f"activity {activity.id} is missing from the DSR")
            continue
        if (float(attrs.get("start_s", -1)), float(attrs.get("end_s", -1))) != (activity.start_s, activity.end_s) \
                or attrs.get("object") != activity.object or (attrs.get("state") == "cancelled") != activity.cancelled:
            lost.append(f"activity {activity.id} in the DSR ({attrs.get('start_s')}-{attrs.get('end_s')}, "
                        f"{attrs.get('state')}) differs from the agenda log ({activity.start_s}-{activity.end_s}, "
                        f"{'cancelled' if activity.cancelled else 'not cancelled'})")
    extra = set(published) - {a.id for a in day.activities}
    lost += [f"activity {a} is in the DSR but not in the agenda log" for a in sorted(extra)]
    return lost


def run_chaos(scene: str | Path, schedule: list[Fault] | None = None, *, seed: int = 0, faults: int = 6,
              duration_s: float = 25.0, timeout_s: float = 300.0, record: bool = True,
              runs_dir: Path | None = None, rate: float | None = None,
              log: Callable[[str], None] | None = None) -> ChaosReport:
    """Launch SCENE, inject the faults (``schedule``, else a random one from ``seed``), report."""
    from scenes.loader import load_scene
    from tools.launch import run_system
    from tools.supervisor import REPO_ROOT

    loaded = load_scene(scene)
    if schedule is None:
        schedule = random_schedule(loaded, seed=seed, faults=faults, duration_s=duration_s)
    chaos = ChaosRun(schedule, log=log)
    kills = sum(1 for f in schedule if f.action == "kill")
    try:
        result = run_system(loaded.path, rate=rate, runs_dir=runs_dir or REPO_ROOT / "recordings",
                            timeout_s=timeout_s, record=record, restart_limit=kills + 3, on_tick=chaos.on_tick)
    finally:
        chaos.finish()
    try:
        requests = chaos.request_states()
        accepted = [f.change for f, o in zip(schedule, chaos.outcomes, strict=True)
                    if f.action == "agenda" and o.injected and o.note == "accepted" and f.change]
        graph = chaos.graph
        if graph is not None:
            lost = lost_writes(graph, loaded, chaos.done_seen | {m for m, a in result.missions.items()
                                                                 if a.get("state") == "done"}, accepted)
            missions = {str(n.attrs.get("mission_id", n.name)): str(n.attrs.get("state"))
                        for n in graph.nodes_of_type("mission")}
        else:
            lost, missions = ["the chaos replica never joined the graph"], {}
        if graph is not None:
            graph.save(str(result.run_dir / "final_graph.json"))
    finally:
        chaos.close()
    pending = [name for name, state in requests.items() if state not in ("accepted", "refused")]
    # Faults the run outlived are reported (faults_injected < faults_planned), not failures.
    ok = (result.ok and not lost and not pending and chaos.final_converged
          and all(o.converged_s is not None for o in chaos.outcomes if o.injected))
    report = ChaosReport(scene=loaded.scene.name, ok=ok, faults=chaos.outcomes, missions=missions,
                         writes_lost=len(lost), lost=lost, requests=requests, final_converged=chaos.final_converged,
                         final_divergence=chaos.final_divergence,
                         restarts=result.restarts, wall_s=result.wall_s, run_dir=str(result.run_dir),
                         rrd=str(result.rrd_path) if result.rrd_path else None, events=result.events)
    (result.run_dir / "chaos.json").write_text(json.dumps(report.summary(), indent=2))
    return report


# ----------------------------------------------------------------------------- CLI
def _table(summary: dict[str, Any]) -> Any:
    from rich.table import Table

    table = Table(title=f"chaos on {summary['scene']}: {'OK' if summary['ok'] else 'FAILED'}")
    for column in ("#", "fault", "at (wall s)", "sim", "mission", "recovered s", "converged s", "note"):
        table.add_column(column)
    for index, fault in enumerate(summary["faults"]):
        table.add_row(str(index), fault["what"], str(fault["at_wall_s"]), _clock(fault["at_sim_s"]), str(fault["mission"]),
                      str(fault["recovered_s"]), str(fault["converged_s"]), fault["note"])
    return table


def register(app: typer.Typer) -> None:
    @app.command("chaos")
    def chaos(scene: str = typer.Argument(..., help="scene file or name in scenes/"),
              seed: int = typer.Option(0, help="random seed of the fault schedule"),
              duration: float = typer.Option(25.0, help="faults fall within this many wall seconds "
                                             "after the first mission starts"),
              faults: int = typer.Option(6, help="number of faults"),
              schedule: Path = typer.Option(None, help="JSON list of faults to run instead of a random schedule"),
              timeout: float = typer.Option(300.0, help="wall-clock limit of the run"),
              no_record: bool = typer.Option(False, "--no-record", help="do not write a Rerun recording"),
              runs_dir: Path = typer.Option(None, help="where the run's directory goes (default: recordings/)"),
              as_json: bool = typer.Option(False, "--json", help="print the summary as one JSON object")) -> None:
        """Launch SCENE under a randomized fault schedule; report faults, missions, convergence, lost writes."""
        from rich.console import Console

        from scenes.yamlio import SourceError

        err = Console(stderr=True)
        try:
            planned = load_schedule(schedule) if schedule is not None else None
            report = run_chaos(scene, planned, seed=seed, faults=faults, duration_s=duration, timeout_s=timeout,
                               record=not no_record, runs_dir=runs_dir, log=lambda text: err.print(f"[chaos] {text}", highlight=False))
        except (SourceError, ChaosError) as exc:
            typer.echo(f"error: {exc}", err=True)
            raise typer.Exit(2) from None
        summary = report.summary()
        if as_json:
            typer.echo(json.dumps(summary))
        else:
            console = Console()
            console.print(_table(summary))
            console.print(f"missions completed {summary['missions_completed']}/{summary['missions_total']}, "
                          f"faults injected {summary['faults_injected']}/{summary['faults_planned']}, "
                          f"convergence max {summary['convergence_max_s']} s, writes lost {summary['writes_lost']}")
            for line in summary["lost"]:
                console.print(f"  lost: {line}")
        raise typer.Exit(0 if report.ok else 1)
