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

"Trust" (``tools.chaos.checks.trust_summary``): at the end, every member's refusal counters must be 0 (faults
are not attacks: no honest state refused after a restart), no member may serve a writer claim about
another that the other does not make, and the state fetches each member made (and held back) are
reported, with the router's ACL denials.  "Writes lost" must be 0: every mission seen ``done`` is still done at the end, every agenda change
answered ``accepted`` is in the agenda's change log exactly once, and the activities the agenda
agent publishes are exactly the scene's agenda with that log replayed (what a restarted agenda
agent rebuilds).  The run itself is `tools.launch.run_system`, unchanged: faults are injected
from a thread fed by its ``on_tick`` status (pids, endpoint, graph).

Modules: ``chaos_schedule`` (faults, random and file schedules), ``chaos_injector`` (the thread that
breaks things and times the recovery), ``chaos_checks`` (digests, divergence, lost writes), and
this one (the run, the report, the CLI).  The run leaves ``chaos.json`` (the summary; its
``faults`` replay with ``--schedule``) and ``final_graph.json`` (the DSR at the end) in its directory.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import typer

from tools.chaos.checks import describe_divergence, lost_writes, probe_replicas
from tools.chaos.injector import CHAOS_AGENT, ChaosRun, FaultOutcome
from tools.chaos.schedule import (ACTIONS, ChaosError, Fault, clock_text, load_schedule,
                                  random_agenda_change, random_schedule)

__all__ = ["ACTIONS", "CHAOS_AGENT", "ChaosError", "ChaosReport", "ChaosRun", "Fault", "FaultOutcome",
           "describe_divergence", "load_schedule", "lost_writes", "probe_replicas", "random_agenda_change",
           "random_schedule", "register", "run_chaos"]


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
    trust: dict[str, Any] = field(default_factory=dict)

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
            "trust": self.trust,
        }


def run_chaos(scene: str | Path, schedule: list[Fault] | None = None, *, seed: int = 0, faults: int = 6,
              duration_s: float = 4.0, timeout_s: float = 300.0, record: bool = True,
              runs_dir: Path | None = None, rate: float | None = None,
              log: Callable[[str], None] | None = None) -> ChaosReport:
    """Launch SCENE, inject the faults (``schedule``, else a random one from ``seed``), report."""
    from agents.world.vocabulary import MissionState, NodeType, RequestState
    from agents.world.scene_world import load_world
    from tools.launch import run_system

    loaded = load_world(scene)
    if schedule is None:
        schedule = random_schedule(loaded, seed=seed, faults=faults, duration_s=duration_s)
    chaos = ChaosRun(schedule, log=log)
    kills = sum(1 for f in schedule if f.action == "kill")
    try:
        result = run_system(loaded.path, rate=rate, runs_dir=runs_dir,
                            timeout_s=timeout_s, record=record, restart_limit=kills + 3, on_tick=chaos.on_tick)
    finally:
        chaos.finish()
    try:
        requests = chaos.request_states()
        accepted = [f.change for f, o in zip(schedule, chaos.outcomes, strict=True)
                    if f.action == "agenda" and o.note == "accepted" and f.change]
        graph = chaos.graph
        if graph is None:
            lost, missions = ["the chaos replica never joined the graph"], {}
        else:
            done = chaos.done_seen | {m for m, a in result.missions.items() if a.get("state") == MissionState.DONE}
            lost = lost_writes(graph, loaded, done, accepted)
            missions = {str(n.attrs.get("mission_id", n.name)): str(n.attrs.get("state"))
                        for n in graph.nodes_of_type(NodeType.MISSION)}
            graph.save(str(result.run_dir / "final_graph.json"))  # the DSR after the run, for tests and people
    finally:
        chaos.close()
    pending = [name for name, state in requests.items() if state not in RequestState.ANSWERED]
    # Faults the run outlived are reported (faults_injected < faults_planned), not failures.
    # Kills, stops and restarts are not hostile: no member may refuse an honest one's state, and
    # no member may serve a claim about another that the other does not make.
    trust = chaos.trust
    honest = bool(trust) and trust.get("refusals_total") == 0 \
        and not trust.get("unproven_claims_served")
    ok = (result.ok and not lost and not pending and chaos.final_converged and honest
          and all(o.converged_s is not None for o in chaos.outcomes if o.injected))
    report = ChaosReport(scene=loaded.scene.name, ok=ok, faults=chaos.outcomes, missions=missions,
                         writes_lost=len(lost), lost=lost, requests=requests, final_converged=chaos.final_converged,
                         final_divergence=chaos.final_divergence,
                         restarts=result.restarts, wall_s=result.wall_s, run_dir=str(result.run_dir),
                         rrd=str(result.rrd_path) if result.rrd_path else None, events=result.events,
                         trust=trust)
    (result.run_dir / "chaos.json").write_text(json.dumps(report.summary(), indent=2))
    return report


# ----------------------------------------------------------------------------- CLI
def _table(summary: dict[str, Any]) -> Any:
    from rich.table import Table

    table = Table(title=f"chaos on {summary['scene']}: {'OK' if summary['ok'] else 'FAILED'}")
    for column in ("#", "fault", "at (wall s)", "sim", "mission", "recovered s", "converged s", "note"):
        table.add_column(column, no_wrap=column not in ("fault", "note"))
    for index, fault in enumerate(summary["faults"]):
        table.add_row(str(index), fault["what"], str(fault["at_wall_s"]), clock_text(fault["at_sim_s"]),
                      str(fault["mission"]), str(fault["recovered_s"]), str(fault["converged_s"]), fault["note"])
    return table


def fault_lines(summary: dict[str, Any], width: int) -> list[str]:
    """The faults as a plain layout for pipes and logs: one entry per fault, wrapped between words
    at ``width`` (the table's eight columns do not fit 80 columns without cutting them)."""
    from tools.plain import wrapped

    lines = [f"chaos on {summary['scene']}: {'OK' if summary['ok'] else 'FAILED'}"]
    for index, fault in enumerate(summary["faults"]):
        text = (f"#{index} {fault['what']} at {fault['at_wall_s']} s wall (sim {clock_text(fault['at_sim_s'])}, "
                f"mission {fault['mission']}): recovered {fault['recovered_s']} s, converged {fault['converged_s']} s"
                + (f"; {fault['note']}" if fault["note"] else ""))
        lines += wrapped(text, width, first="  ", indent="      ")
    return lines


def register(app: typer.Typer) -> None:
    @app.command("chaos")
    def chaos(scene: str = typer.Argument(..., help="scene file or name in scenes/"),
              seed: int = typer.Option(0, help="random seed of the fault schedule"),
              duration: float = typer.Option(4.0, help="each fault falls within this many wall seconds "
                                             "after the start of its mission"),
              faults: int = typer.Option(6, help="number of faults"),
              schedule: Path = typer.Option(None, help="JSON list of faults to run instead of a random schedule"),
              timeout: float = typer.Option(300.0, help="wall-clock limit of the run"),
              no_record: bool = typer.Option(False, "--no-record", help="do not write a Rerun recording"),
              runs_dir: Path = typer.Option(None, help="where the run's directory goes "
                                            "(default: ./recordings or $CHRONAV_RUNS)"),
              as_json: bool = typer.Option(False, "--json", help="print the summary as one JSON object")) -> None:
        """Launch SCENE under a randomized fault schedule; report faults, missions, convergence, lost writes."""
        from rich.console import Console

        from scenes.yamlio import SourceError
        from tools.launch import LaunchError

        err = Console(stderr=True)
        try:
            planned = load_schedule(schedule) if schedule is not None else None
            report = run_chaos(scene, planned, seed=seed, faults=faults, duration_s=duration, timeout_s=timeout,
                               record=not no_record, runs_dir=runs_dir,
                               log=lambda text: err.print(f"[chaos] {text}", highlight=False))
        except (SourceError, ChaosError, LaunchError) as exc:
            typer.echo(f"error: {exc}", err=True)
            raise typer.Exit(2) from None
        summary = report.summary()
        if as_json:
            typer.echo(json.dumps(summary))
        else:
            from tools.plain import console_width, is_plain, print_lines

            console = Console()
            if is_plain(console):
                print_lines(console, fault_lines(summary, console_width(console)))
            else:
                console.print(_table(summary))
            console.print(f"missions completed {summary['missions_completed']}/{summary['missions_total']}, "
                          f"faults injected {summary['faults_injected']}/{summary['faults_planned']}, "
                          f"convergence max {summary['convergence_max_s']} s, writes lost {summary['writes_lost']}")
            for line in summary["lost"]:
                console.print(f"  lost: {line}")
            trust = summary.get("trust") or {}
            console.print(f"refusals {trust.get('refusals_total')} {trust.get('refusals') or ''}, "
                          f"unproven claims served {len(trust.get('unproven_claims_served') or [])}, "
                          f"router ACL denials {trust.get('router_acl_denied')}")
        raise typer.Exit(0 if report.ok else 1)
