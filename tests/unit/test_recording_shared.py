"""An in-process run writes every agent through one Rerun stream (issue 41: a week in one process).

rerun-sdk 0.41 never frees a RecordingStream (rerun-io/rerun#2116), so seven streams a day grew an
in-process week by about 20 MB a day; agents/runtime/recording.py's RecordingFile is the one
stream of a run, shared by its Recorders.
"""

from __future__ import annotations

import datetime as dt
import subprocess
from pathlib import Path

import pytest

from agents.runtime.recording import ROTATE_ENV, Recorder, RecordingFile, part_slot
from tests.support import recording_entities

DAY = dt.date(2026, 12, 1)
TINY = Path(__file__).resolve().parents[1] / "data" / "eval_tiny.yaml"


def test_recorders_sharing_a_file_write_one_part_and_only_its_owner_closes_it(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import rerun as rr

    monkeypatch.setenv("RERUN", "on")
    monkeypatch.delenv(ROTATE_ENV, raising=False)
    shared = RecordingFile("inprocess", tmp_path, "rid")
    sim = Recorder("sim_robot", tmp_path, "rid", day=DAY, file=shared)
    executive = Recorder("executive", tmp_path, "rid", day=DAY, file=shared)
    sim.set_time(9 * 3600.0)
    sim.log("world/truth/robot", rr.Points2D([[1.0, 2.0]]))
    sim.close()                                   # an agent's recorder closes first ...
    executive.set_time(9 * 3600.0 + 1.0)
    executive.event("09:00:01 mission m1 started")   # ... and the stream still writes
    assert not sim.enabled or sim.path is None
    shared.close()
    (part,) = sorted((tmp_path / "rrd").glob("*.rrd"))
    assert part.name.startswith("inprocess-")
    assert {"world/truth/robot", "events/executive"} <= recording_entities(part)


def test_a_shared_file_rotates_once_for_all_its_recorders_with_every_ones_static_rows(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import rerun as rr

    monkeypatch.setenv("RERUN", "on")
    monkeypatch.setenv(ROTATE_ENV, "3600")
    shared = RecordingFile("inprocess", tmp_path, "rid")
    launcher = Recorder("launcher", tmp_path, "rid", day=DAY, file=shared)
    sim = Recorder("sim_robot", tmp_path, "rid", day=DAY, file=shared)
    launcher.line_strip("world/map/walls", [[0, 0], [6, 0]], color=[0, 0, 0], static=True)
    sim.log("legend/robot", rr.TextDocument("robot"), static=True)
    for sim_s in (9 * 3600 + 5.0, 9 * 3600 + 60.0, 10 * 3600 + 1.0):
        sim.set_time(sim_s)
        sim.log("world/truth/robot", rr.Points2D([[sim_s / 3600, 0]]))
        launcher.set_time(sim_s)
    shared.close()
    parts = sorted((tmp_path / "rrd").glob("*.rrd"))
    assert [part_slot(p) for p in parts] == [9, 10]
    for part in parts:
        assert {"world/map/walls", "legend/robot", "world/truth/robot"} <= recording_entities(part)


def test_an_in_process_run_opens_one_recording_stream(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Through the runner `chronav launch --in-process` uses: one stream for six agents and the
    launcher (it was seven, one each, and none is ever freed)."""
    import rerun as rr

    from tools.inprocess import run_in_process

    monkeypatch.setenv("RERUN", "on")
    monkeypatch.delenv(ROTATE_ENV, raising=False)
    made: list[str] = []
    real = rr.RecordingStream

    class Counting(real):  # type: ignore[misc,valid-type]
        def __init__(self, *args: object, **kwargs: object) -> None:
            made.append(str(kwargs.get("recording_id")))
            super().__init__(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(rr, "RecordingStream", Counting)
    result = run_in_process(TINY, runs_dir=tmp_path, record=True, timeout_s=300)
    assert result.error is None and result.rrd_path is not None and result.rrd_path.stat().st_size > 0
    assert made == [result.run_dir.name]
    entities = recording_entities(result.rrd_path)
    assert {"events/executive", "events/sim_robot"} <= entities
    assert any(e.startswith("world/map/") for e in entities) and any(e.startswith("world/truth/") for e in entities)


def test_parts_are_written_without_footer_and_the_merge_writes_it(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A part's footer made the SDK hold every chunk's entry in memory while the file was open (an
    agent's memory climbed all day in real time); the merged recording users open has one."""

    from tools.launch import merge_recordings, rerun_binary

    monkeypatch.setenv("RERUN", "on")
    monkeypatch.delenv(ROTATE_ENV, raising=False)
    recorder = Recorder("agenda", tmp_path, "rid", day=DAY)
    for step in range(5):
        recorder.set_time(9 * 3600.0 + step)
        recorder.scalar("metrics/objects/tv", float(step))
        recorder.flush()
    part = recorder.path
    recorder.close()
    assert part is not None

    def verified(path: Path) -> bool:
        return subprocess.run([str(rerun_binary()), "rrd", "verify", str(path)], capture_output=True,
                              timeout=60, check=False).returncode == 0

    assert not verified(part)
    merged = merge_recordings([part], tmp_path / "run.rrd")
    assert merged is not None and verified(merged) and "metrics/objects/tv" in recording_entities(merged)
