"""Issue 7, faults during missions: every agent and the router SIGKILLed in turn while missions run.

One run of icra_usecase (four missions) through `chronav chaos --schedule`, two kills per mission
plus an agenda change: the launcher restarts each process, the restarted replica resumes from
the replicated state, the missions complete, nothing acknowledged is lost, and the recording of
every process (killed ones included) reads back with Rerun's own API.  A second, shorter run
drives the randomized schedule of `chronav chaos`.  The pure parts of tools/chaos/command.py (schedules,
the lost-write check) are tested offline, on the same schedule: tests/unit/test_chaos_schedule.py.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from agents.lib.metrics.metrics import read_trajectory_csv
from dsr import DSRGraph
from scenes.loader import load_scene
from scenes.clock import parse_clock
from tests.support import REPO_ROOT
from tests.system.launch_helpers import run_json
from tools.launch import agent_names

MISSIONS = ("m0930", "m1045", "m1115", "m1315")
#: Two kills per mission and an agenda change, each fault waiting for the previous one to converge
#: (the schedule file a user passes to `chronav chaos --schedule`).
SCHEDULE = REPO_ROOT / "tests" / "data" / "chaos_kills.json"
KILLS: list[dict[str, Any]] = json.loads(SCHEDULE.read_text())


# ----------------------------------------------------------------------------- the system
def _chaos(args: list[str], log: Path, timeout_s: float) -> dict[str, Any]:
    """The run's summary, plus the lines of its log saying the launcher did not end cleanly: a thread
    still running at its exit (agents/runtime/exit_guard.py) or glibc's abort of one inside Zenoh."""
    summary = run_json(["chaos", *args], log, timeout_s)
    summary["exit_problems"] = [line for line in log.read_text().splitlines()
                                if "FATAL" in line or "still running" in line]
    return summary


slow = pytest.mark.slow


@pytest.fixture(scope="module")
def kill_run(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    work = tmp_path_factory.mktemp("faults")
    return _chaos(["icra_usecase", "--schedule", str(SCHEDULE), "--runs-dir", str(work)], work / "chaos.log", 240)


@slow
def test_every_process_killed_during_a_mission_and_the_missions_complete(kill_run: dict[str, Any]) -> None:
    assert kill_run["returncode"] == 0 and kill_run["ok"], json.dumps(kill_run, indent=1)[:4000]
    assert kill_run["exit_problems"] == []
    assert kill_run["missions"] == dict.fromkeys(MISSIONS, "done")
    assert kill_run["faults_injected"] == len(KILLS)
    for fault in kill_run["faults"]:
        assert fault["mission"] is not None, f"{fault['what']} was not during a mission"
        assert fault["converged_s"] is not None, f"replicas did not converge after {fault['what']}"
    assert kill_run["restarts"] == dict.fromkeys([*agent_names(), "router"], 1)
    assert kill_run["final_converged"]


@slow
def test_no_member_refuses_an_honest_one_after_the_restarts(kill_run: dict[str, Any]) -> None:
    """Issue #31: after restarts, members refused parts of honest states as forged_stamp (an
    old removal some had compacted); and replicas served writer claims they could not prove.
    Every process was killed and restarted here: every refusal counter stays at 0, no claim is
    served unproven, and each member fetched states a bounded number of times."""
    trust = kill_run["trust"]
    assert trust["refusals_total"] == 0, trust["refusals"]
    assert trust["unproven_claims_served"] == [], trust["unproven_claims_served"]
    assert set(agent_names()) <= set(trust["fetches"])
    # Digest-triggered fetches: at most 5 per member in a first burst (pauses 2, 4, 8, 16 s),
    # then one per 30 s (dsr/transport.py _fetch_allowed), whatever the load.
    wall, members = kill_run["wall_s"], len(trust["fetches"]) - 1
    for agent, counts in trust["fetches"].items():
        assert counts["anti_entropy"] <= members * (5 + wall / 30), (agent, counts, wall)


@slow
def test_nothing_acknowledged_is_lost(kill_run: dict[str, Any]) -> None:
    assert kill_run["writes_lost"] == 0, kill_run["lost"]
    assert list(kill_run["agenda_requests"].values()) == ["accepted"]
    graph = DSRGraph.load(str(Path(kill_run["run_dir"]) / "final_graph.json"), agent="test")
    extra = graph.get_node_by_name("activity/faults_extra")  # accepted before the agenda agent died
    assert extra is not None and (extra.attrs["start_s"], extra.attrs["end_s"]) == (parse_clock("13:00"),
                                                                                     parse_clock("13:40"))
    # A restarted executive resumes its missions: no second copy, no mission left behind.
    assert sorted(n.name for n in graph.nodes_of_type("mission")) == [f"mission/{m}" for m in MISSIONS]
    for mission in MISSIONS:
        node = graph.get_node_by_name(f"mission/{mission}")
        assert node.attrs["state"] == "done" and node.attrs["plan"], node.attrs
    # ...and a finished mission's intentions leave with its end, in one transaction, restarts or not.
    assert graph.nodes_of_type("intention") == []


@slow
def test_restarted_agents_resume_from_the_replicated_state(kill_run: dict[str, Any]) -> None:
    run_dir = Path(kill_run["run_dir"])
    at = {f["fault"]["target"]: f["at_sim_s"] for f in kill_run["faults"] if f["fault"]["action"] == "kill"}
    # The simulator went on from the replicated pose and clock: time never goes back (the reader
    # checks) and the robot never jumps (a restart from the scene's start pose would).
    scene = load_scene("icra_usecase").scene
    track = read_trajectory_csv(run_dir / "trajectory.csv")
    assert track[0, 0] < at["sim_robot"] < track[-1, 0]
    steps = np.hypot(np.diff(track[:, 1]), np.diff(track[:, 2]))
    limit = scene.robot.max_speed * np.maximum(np.diff(track[:, 0]), 0.1) * 1.5 + 0.01
    assert np.all(steps <= limit), f"robot jumped {steps.max():.2f} m at t={track[1 + np.argmax(steps - limit), 0]:.1f}"
    graph = DSRGraph.load(str(run_dir / "final_graph.json"), agent="test")
    # The restarted observer republished everyone; the restarted recognition kept every object.
    people = graph.nodes_of_type("person")
    assert {p.name for p in people} == {p.name for p in scene.people}
    assert all(p.attrs["seen_s"] >= at["human_observer"] for p in people)
    assert {o.name for o in graph.nodes_of_type("object")} == {o.name for o in scene.objects}
    assert all(graph.world_pose(o.id) for o in graph.nodes_of_type("object"))
    clock = graph.get_node_by_name("clock")
    assert clock.attrs["now_s"] >= max(at.values())


# What each agent logs under its own entity; the continuous ones must cover both sides of the kill.
LOGGED = {"sim_robot": ("/world/truth/robot/body", True), "human_observer": ("/world/belief/people/positions", True),
          "agenda": ("/metrics/objects/tv", True), "social_navigation": ("/world/decision/path", False),
          "executive": ("/events/executive", False), "object_recognition": ("/events/object_recognition", False)}


@slow
@pytest.mark.filterwarnings("ignore:RRD file has no footer")  # the killed processes' files, on purpose
def test_the_recording_of_every_process_reads_back(kill_run: dict[str, Any]) -> None:
    from tests.system.recording import load_store, texts

    run_dir = Path(kill_run["run_dir"])
    # merged, the per-process parts (the killed processes' ones without a footer among them) are
    # removed: the merged recording below holds every process's rows, across each kill
    assert not list((run_dir / "rrd").glob("*.rrd")), "the merged parts are removed"
    store = load_store(Path(kill_run["rrd"]))
    killed_at = {f["fault"]["target"]: f["at_sim_s"] for f in kill_run["faults"] if f["fault"]["action"] == "kill"}
    for agent, (entity, continuous) in LOGGED.items():
        table = store.reader(index="sim_time", contents=entity).to_arrow_table()
        times = [t.total_seconds() for t in table.column("sim_time").to_pylist()]
        assert times, f"nothing of {agent} ({entity}) in the merged recording"
        if continuous:
            assert min(times) < killed_at[agent] < max(times), f"{entity} does not span the kill of {agent}"
    done = [text for _, text in texts(store, "/events/executive") if " done" in text]
    assert all(any(f"mission {m} done" in text for text in done) for m in MISSIONS), done
    poses = store.reader(index="sim_time", contents="/world/truth/robot/body").to_arrow_table()
    times = [t.total_seconds() for t in poses.column("sim_time").to_pylist()]
    assert min(times) <= parse_clock("09:30") and max(times) >= parse_clock("13:15")


# ----------------------------------------------------------------------------- randomized
@slow
def test_a_short_random_chaos_run_loses_nothing(tmp_path: Path) -> None:
    """`chronav chaos` with its own random schedule on a two-mission day (a kill, an agenda
    change, a stop and the router killed, for seed 8)."""
    text = (Path(load_scene("icra_usecase").path)).read_text()
    scene = tmp_path / "icra_short.yaml"
    scene.write_text("\n".join(line for line in text.splitlines()
                                if "{id: m1115" not in line and "{id: m1315" not in line))
    summary = _chaos([str(scene), "--seed", "8", "--faults", "4", "--duration", "3", "--no-record",
                      "--runs-dir", str(tmp_path)], tmp_path / "chaos.log", 200)
    assert summary["returncode"] == 0 and summary["ok"], json.dumps(summary, indent=1)[:4000]
    assert summary["exit_problems"] == []    # every thread of the launcher closed before it ended
    assert summary["missions_completed"] == summary["missions_total"] == 2
    assert summary["faults_injected"] >= 3 and summary["writes_lost"] == 0
    assert math.isfinite(summary["convergence_max_s"])
