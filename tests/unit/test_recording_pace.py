"""A real-time run draws by sim time, not by loop (issue 41: bounded disk in real time).

Agents loop at 50 Hz of wall time.  In a fast run a loop covers a second of sim time or more; in
real time every loop drew the simulator's whole world and the agenda's R(t), and a two-hour soak's
parts grew by 300-500 MB an hour.  The true world is drawn every 0.1 sim s, R(t) every sim second,
and a rotating (real-time) stream flushes every REALTIME_FLUSH_S instead of every 0.2 s.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from agents.agenda.agent import R_DRAW_EVERY_S, AgendaAgent
from agents.object_recognition.agent import ObjectRecognitionAgent
from agents.runtime.config import AgentConfig
from agents.runtime.recording import ROTATE_ENV, FramePacer, Recorder
from agents.sim_robot.agent import DRAW_EVERY_S, SimRobotAgent
from dsr import DSRGraph
from scenes.loader import SCENES_DIR
from tests.support import rrd_print

SCENE = SCENES_DIR / "icra_usecase.yaml"


def test_a_pacer_is_due_once_per_period_of_sim_time_and_again_when_the_clock_goes_back() -> None:
    pacer = FramePacer(0.5)
    ticks = [0.1 * k for k in range(21)]       # 0.1 s ticks: their float sums are not exact
    drawn = [t for t in ticks if pacer.due(t)]
    assert drawn == pytest.approx([0.0, 0.5, 1.0, 1.5, 2.0])
    assert not pacer.due(2.1)
    assert pacer.due(0.3)                      # a new day (or a restarted clock) draws at once


def _rows(part: Path, entity: str) -> list[float]:
    """Sim seconds of every row of ``entity`` in a recording part (footer or not)."""
    from rerun.chunk import RrdReader

    table = RrdReader(str(part)).stream().collect().reader(index="log_time", contents=entity).to_arrow_table()
    return sorted(t.total_seconds() for t in table.column("sim_time").to_pylist() if t is not None)


def test_a_real_time_simulator_and_agenda_draw_by_sim_time_not_by_loop(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("RERUN", "on")
    monkeypatch.setenv(ROTATE_ENV, "3600")          # a real-time run's recording (tools/launch.hourly_rotation)
    graph = DSRGraph(agent="test")
    config = {"scene": SCENE, "run_dir": tmp_path, "recording_id": "rid"}
    sim = SimRobotAgent(AgentConfig(name="sim_robot", options={"busy_rate": "1"}, **config))
    sim_rec = Recorder("sim_robot", tmp_path, "rid")
    sim.setup(graph, sim_rec)
    # an intention being planned: the clock runs at the busy rate (real time), as while agents plan
    graph.insert_node(type="intention", name="intention/m/0", attrs={"state": "active", "kind": "navigate"})
    objects = ObjectRecognitionAgent(AgentConfig(name="object_recognition", scene=SCENE))
    objects.setup(graph, Recorder("object_recognition", None, None))
    agenda = AgendaAgent(AgentConfig(name="agenda", **config))
    agenda_rec = Recorder("agenda", tmp_path, "rid")
    agenda.setup(graph, agenda_rec)
    wall = [1000.0]
    sim.wall_clock = lambda: wall[0]               # the agents' loop, 50 Hz of wall time, 150 loops
    start_s = sim.now_s
    for _ in range(150):
        sim.step()
        objects.step()
        agenda.step()
        wall[0] += 0.02
    span_s = sim.now_s - start_s
    sim_rec.close()
    agenda_rec.close()
    assert 2.5 < span_s < 3.5                      # real time: a sim second a wall second
    (sim_part,) = (tmp_path / "rrd").glob("sim_robot-*-s*.rrd")
    (agenda_part,) = (tmp_path / "rrd").glob("agenda-*-s*.rrd")
    bodies = _rows(sim_part, "/world/truth/robot/body")
    assert 0.8 * span_s / DRAW_EVERY_S <= len(bodies) <= span_s / DRAW_EVERY_S + 2   # was one a loop
    assert min(b - a for a, b in zip(bodies, bodies[1:], strict=False)) >= DRAW_EVERY_S - 1e-6
    r_rows = _rows(agenda_part, "/metrics/objects/tv")
    assert 1 <= len(r_rows) <= span_s / R_DRAW_EVERY_S + 2


def _chunks(part: Path, entity: str) -> int:
    """How many chunks of ``entity`` a part holds, as ``rerun rrd print`` lists them."""
    return sum(1 for line in rrd_print(part).splitlines() if line.startswith("Chunk(") and f" - {entity} - " in line)


@pytest.mark.parametrize("real_time", [True, False])
def test_a_real_time_stream_flushes_seconds_of_rows_per_chunk(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, real_time: bool) -> None:
    """Each flush writes a chunk per entity, about 1.6 kB of framing: a real-time agent flushing
    every 0.2 s wrote more framing than data.  A fast run keeps Rerun's 0.2 s (it flushes rarely
    in sim time anyway, and a kill loses less)."""
    import time

    import rerun as rr

    monkeypatch.setenv("RERUN", "on")
    if real_time:
        monkeypatch.setenv(ROTATE_ENV, "3600")
    else:
        monkeypatch.delenv(ROTATE_ENV, raising=False)
    recorder = Recorder("sim_robot", tmp_path, "rid")
    for k in range(24):                           # 1.2 s of wall time, a row every 50 ms
        recorder.set_time(9 * 3600.0 + 0.05 * k)
        recorder.log("world/truth/robot", rr.Points2D([[0.0, 0.05 * k]]))
        time.sleep(0.05)
    recorder.close()
    (part,) = (tmp_path / "rrd").glob("sim_robot-*.rrd")
    chunks = _chunks(part, "/world/truth/robot")
    assert (chunks <= 2) if real_time else (chunks >= 4)
