"""A thin Rerun layer: one file per agent process, all sharing the run's recording id.

Why per-process files merged by the launcher (see shared notes on Rerun 0.41): it survives any
agent being SIGKILLed (the file keeps all but the last ~200 ms), needs no sink process to be up
first, and ``rerun rrd optimize`` turns the files into ONE recording because the recording id is
shared.  Every agent logs under its own entity subtree so rows never collide.  Algorithms never
call Rerun; agents hand their results to this layer.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

APP_ID = "chronav"
TIMELINE = "sim_time"


class Recorder:
    """Logs to ``<run_dir>/rrd/<agent>-<pid>.rrd``; a no-op when disabled (tests, RERUN=off)."""

    def __init__(self, agent: str, run_dir: Path | None, recording_id: str | None) -> None:
        self.agent = agent
        self.enabled = bool(run_dir and recording_id and os.environ.get("RERUN", "on") != "off")
        self._rec: Any = None
        self.path: Path | None = None
        if not self.enabled:
            return
        import rerun as rr

        assert run_dir is not None
        out_dir = run_dir / "rrd"
        out_dir.mkdir(parents=True, exist_ok=True)
        # pid in the name: a restarted agent must not overwrite what its predecessor recorded.
        self.path = out_dir / f"{agent}-{os.getpid()}.rrd"
        self._rec = rr.RecordingStream(APP_ID, recording_id=recording_id)
        self._rec.save(self.path)

    def set_time(self, sim_s: float) -> None:
        """Seconds since local midnight of the sim day, so the viewer reads as a clock."""
        if self._rec is not None:
            import rerun as rr

            rr.set_time(TIMELINE, duration=sim_s, recording=self._rec)

    def log(self, entity: str, *archetypes: Any, static: bool = False) -> None:
        if self._rec is not None:
            self._rec.log(entity, *archetypes, static=static)

    def scalar(self, entity: str, value: float) -> None:
        if self._rec is not None:
            import rerun as rr

            self._rec.log(entity, rr.Scalars(float(value)))

    def event(self, text: str, level: str = "INFO") -> None:
        """Agent decisions as text, one log per agent under ``events/<agent>``."""
        if self._rec is not None:
            import rerun as rr

            self._rec.log(f"events/{self.agent}", rr.TextLog(text, level=getattr(rr.TextLogLevel, level)))

    def line_strip(self, entity: str, points: Sequence[Sequence[float]], color: Sequence[int],
                   radius: float = 0.03, static: bool = False) -> None:
        if self._rec is not None and len(points) >= 2:
            import rerun as rr

            self._rec.log(entity, rr.LineStrips2D([list(map(list, points))], colors=[color], radii=radius),
                          static=static)

    def send_blueprint(self, blueprint: Any) -> None:
        if self._rec is not None:
            self._rec.send_blueprint(blueprint)

    def flush(self) -> None:
        if self._rec is not None:
            self._rec.flush()

    def close(self) -> None:
        """Flush and write the footer (only a clean disconnect writes it)."""
        if self._rec is not None:
            self._rec.disconnect()
            self._rec = None
