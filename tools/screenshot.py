"""Render a recording to PNGs headless: one instant, or a tour of every mission (docs, reviews, CI).

Usage:
  python -m tools.screenshot RECORDING.rrd OUT.png [--at HH:MM[:SS]] [--size 1600x900]
  python -m tools.screenshot RECORDING.rrd OUT_DIR --tour [--size 1600x900]
  python -m tools.screenshot RUN/index.json OUT.png --day 2 [--at HH:MM]   (a run of days, docs/long_runs.md)

Without ``--at`` the picture is at the recording's last instant (its last ``sim_time`` row).
``--tour`` writes three PNGs per mission into OUT_DIR: its start (the first path the navigation
adopted for it), the robot's closest approach to a person during it (from the recording's true positions) and its arrival (done or failed), named
``<mission>-1-start-HHMMSS.png`` ...; the instants come from the executive's events and the
world layer of the recording itself, so the tour needs nothing but the .rrd.

Needs a Vulkan software driver on headless Linux (Debian: mesa-vulkan-drivers), and Rerun's
DataFusion reader (``rerun-sdk[catalog]``, in the test extra that `make demo` and `make test` install).

Why the settle adapts: the viewer loads the file, then renders on the CPU (llvmpipe); a big
recording on a busy machine is not ready after a fixed 4 s and the viewer then answers the
screenshot request with a TimeoutError.  The tool waits until the recording is open and then
retries the screenshot with growing pauses, within a budget that grows with the file's size
(``--settle`` is only the first pause, and ``--timeout`` overrides the budget).
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import re
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tools.ports import free_port, port_open

DEFAULT_SIZE = "1600x900"
BASE_BUDGET_S = 45.0
BUDGET_PER_MB_S = 1.5
MAX_BUDGET_S = 600.0
TIMELINE = "sim_time"
CLOCK_TIMELINE = "clock"
MISSION_STARTED = re.compile(r"mission (\S+) \((.*)\) started")
MISSION_ENDED = re.compile(r"mission (\S+) (done|failed)")
PATH_ADOPTED = re.compile(r"social_navigation: path ")


class ScreenshotError(RuntimeError):
    """What went wrong, in the user's words (printed without a traceback)."""


@dataclass(frozen=True)
class Stop:
    """One picture of a tour: a mission, what the instant is, and when (sim s of the day)."""

    mission: str
    what: str
    sim_s: float


def parse_size(text: str) -> tuple[int, int]:
    match = re.fullmatch(r"\s*(\d{2,5})\s*[xX]\s*(\d{2,5})\s*", text)
    if not match:
        raise argparse.ArgumentTypeError(f"--size {text!r}: expected WIDTHxHEIGHT in pixels, e.g. 1600x900")
    width, height = int(match.group(1)), int(match.group(2))
    if not (200 <= width <= 8000 and 200 <= height <= 8000):
        raise argparse.ArgumentTypeError(f"--size {text!r}: each side must be 200..8000 pixels")
    return width, height


def budget_s(recording: Path) -> float:
    """How long the viewer may take to load and render ``recording`` before we give up."""
    size_mb = recording.stat().st_size / 1e6
    return min(MAX_BUDGET_S, BASE_BUDGET_S + BUDGET_PER_MB_S * size_mb)


# ----------------------------------------------------------------------------- reading the recording
def load_store(recording: Path) -> Any:
    from rerun.chunk import RrdReader

    return RrdReader(str(recording)).stream().collect()


def _seconds(value: Any) -> float:
    return value.total_seconds() if hasattr(value, "total_seconds") else float(value) / 1e9


def end_of(store: Any) -> float:
    """The last ``sim_time`` of the recording, over every entity (the robot's last pose is the
    usual one, but a recording may end with a report or an event)."""
    table = store.reader(index=TIMELINE, contents="/**").select(TIMELINE).to_arrow_table()
    times = [_seconds(t) for t in table.column(TIMELINE).to_pylist() if t is not None]
    if not times:
        raise ScreenshotError("the recording holds no data on the sim_time timeline: is it a chronav run?")
    return max(times)


def _column(store: Any, entity: str, field: str) -> list[tuple[float, Any]]:
    """(sim s, value) of every row of ``entity:field``, in sim-time order.  Indexed by
    ``log_time``: rows logged at the same sim time (an event and the plan logged with it) are one
    row per index value in a ``sim_time`` query, and one of them would be lost."""
    try:
        table = store.reader(index="log_time", contents=entity).to_arrow_table()
    except ValueError:
        return []
    name = f"{entity}:{field}"
    if name not in table.column_names or TIMELINE not in table.column_names:
        return []
    rows = [(_seconds(t), v) for t, v in zip(table.column(TIMELINE).to_pylist(), table.column(name).to_pylist(),
                                             strict=True) if v is not None and t is not None]
    return sorted(rows, key=lambda row: row[0])


def mission_windows(store: Any) -> list[tuple[str, float, float | None]]:
    """(mission id, start, end or None) from the executive's events, in start order."""
    starts: dict[str, float] = {}
    ends: dict[str, float] = {}
    for when, texts in _column(store, "/events/executive", "TextLog:text"):
        for text in texts:
            if (found := MISSION_STARTED.search(text)) is not None:
                starts.setdefault(found.group(1), when)
            elif (found := MISSION_ENDED.search(text)) is not None:
                ends[found.group(1)] = when
    return sorted(((m, s, ends.get(m)) for m, s in starts.items()), key=lambda w: w[1])


def tour_stops(store: Any) -> list[Stop]:
    """Start, closest approach to a person, and arrival of every mission in the recording."""
    import numpy as np

    robot = [(t, np.asarray(v, dtype=float).reshape(-1, 2)[0])
             for t, v in _column(store, "/world/truth/robot/body", "Points2D:positions")]
    people = [(t, np.asarray(v, dtype=float).reshape(-1, 2))
              for t, v in _column(store, "/world/truth/people", "Points2D:positions")]
    people_times = np.array([t for t, _ in people])
    last = end_of(store)
    # The start is shown when the navigation adopted its first path (the map it planned on is then
    # in the decision layer), or at the mission's start if it never planned.
    planned = [t for t, texts in _column(store, "/events/social_navigation", "TextLog:text")
               if any(PATH_ADOPTED.search(text) for text in texts)]
    stops: list[Stop] = []
    for mission, start, end in mission_windows(store):
        finish = end if end is not None else last
        first_path = next((t for t in planned if start <= t <= finish), start)
        stops.append(Stop(mission, "start", first_path))
        best: tuple[float, float] | None = None
        for t, xy in robot:
            if not start <= t <= finish or not len(people_times):
                continue
            k = int(np.searchsorted(people_times, t, side="right")) - 1
            if k < 0 or not len(people[k][1]):
                continue
            distance = float(np.min(np.hypot(*(people[k][1] - xy).T)))
            if best is None or distance < best[0]:
                best = (distance, t)
        if best is not None:
            stops.append(Stop(mission, f"closest-{best[0]:.2f}m", best[1]))
        stops.append(Stop(mission, "arrival" if end is not None else "end-of-recording", finish))
    return stops


def clock_offset_s(store: Any) -> float | None:
    """``clock`` minus ``sim_time`` (POSIX s of the scene day's midnight), or None without a clock."""
    try:
        table = store.reader(index=TIMELINE, contents="/world/truth/robot/body").to_arrow_table()
    except ValueError:
        return None
    if CLOCK_TIMELINE not in table.column_names or table.num_rows == 0:
        return None
    sim = table.column(TIMELINE)[0].as_py()
    clock = table.column(CLOCK_TIMELINE)[0].as_py()
    if clock is None or sim is None:
        return None
    clock_s = clock.replace(tzinfo=dt.UTC).timestamp() if isinstance(clock, dt.datetime) else clock / 1e9
    return clock_s - _seconds(sim)


# ----------------------------------------------------------------------------- the viewer
def _wait_port(port: int, process: subprocess.Popen[bytes], deadline: float) -> None:
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise ScreenshotError(f"the headless viewer exited (code {process.returncode}); is a Vulkan driver "
                                  "installed? (Debian: apt-get install mesa-vulkan-drivers)")
        if port_open(port):
            return
        time.sleep(0.1)
    raise ScreenshotError("the headless viewer did not start listening in time")


class Viewer:
    """A headless Rerun viewer of the pinned SDK at a given window size, driven over gRPC."""

    def __init__(self, size: tuple[int, int], log_path: Path | None = None) -> None:
        import rerun_cli

        binary = str(Path(rerun_cli.__file__).parent / "rerun")
        self.port = free_port()
        env = {**os.environ, "RERUN_APP_ONLY": "true", "WGPU_BACKEND": os.environ.get("WGPU_BACKEND", "vulkan")}
        self._log = open(log_path or os.devnull, "wb")   # noqa: SIM115 - closed in close()
        self.process = subprocess.Popen(
            [binary, "--headless", "--window-size", f"{size[0]}x{size[1]}", "--port", str(self.port),
             "--memory-limit", "75%", "--hide-welcome-screen"],
            stdout=self._log, stderr=subprocess.STDOUT, env=env, start_new_session=True)
        try:
            _wait_port(self.port, self.process, time.monotonic() + 30.0)
            from rerun.experimental import ViewerClient

            self.client = ViewerClient.connect(f"rerun+http://127.0.0.1:{self.port}/proxy")
        except BaseException:
            self.close()
            raise

    def open(self, recording: Path, deadline: float) -> None:
        self.client.open(str(recording.resolve()))
        while time.monotonic() < deadline:   # the recording is open once it is the active one
            try:
                if self.client.get_state().active_recording:
                    return
            except Exception:  # noqa: BLE001 - the viewer may not answer while it loads
                pass
            time.sleep(0.5)
        raise ScreenshotError(f"the viewer did not open {recording} in time")

    def set_time(self, sim_s: float, offset_s: float | None) -> None:
        if offset_s is not None:
            self.client.set_time(CLOCK_TIMELINE, timestamp=_clock_ns(offset_s, sim_s), play_state="paused")
        else:
            self.client.set_time(TIMELINE, duration=sim_s, play_state="paused")

    def shoot(self, out: Path, first_pause_s: float, deadline: float) -> None:
        """Save a screenshot, retrying with growing pauses while the viewer is still busy."""
        pause = first_pause_s
        last: Exception | None = None
        while True:
            time.sleep(min(pause, max(0.0, deadline - time.monotonic())))
            try:
                self.client.save_screenshot(str(out.resolve()))
                if out.exists() and out.stat().st_size > 0:
                    return
            except TimeoutError as exc:   # llvmpipe did not finish the frame: wait and try again
                last = exc
            if time.monotonic() >= deadline:
                raise ScreenshotError(f"the viewer did not render {out.name} within the budget "
                                      f"(last error: {last}); try a smaller --size or a larger --timeout")
            pause = min(pause * 2, 20.0)

    def close(self) -> None:
        try:
            if self.process.poll() is None:
                self.process.terminate()
                try:
                    self.process.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    self.process.kill()
                    self.process.wait(timeout=10)
        finally:
            self._log.close()


def _clock_ns(offset_s: float, sim_s: float) -> Any:
    import numpy as np

    return np.datetime64(int(round(offset_s)) * 1_000_000_000 + int(round(sim_s * 1e9)), "ns")


def _hhmmss(sim_s: float) -> str:
    whole = int(sim_s)
    return f"{whole // 3600:02d}{whole % 3600 // 60:02d}{whole % 60:02d}"


# ----------------------------------------------------------------------------- command line
def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tools.screenshot", description=__doc__.splitlines()[0])
    parser.add_argument("recording", type=Path, help="a .rrd, or the index.json of a run of days (with --day)")
    parser.add_argument("--day", type=int, default=None,
                        help="with an index.json: the day (1-based) to open (default: the last day recorded)")
    parser.add_argument("out", type=Path, help="the PNG to write (with --tour: the folder for the PNGs)")
    parser.add_argument("--at", default=None, help="sim time HH:MM[:SS] (default: the recording's last instant)")
    parser.add_argument("--size", type=parse_size, default=parse_size(DEFAULT_SIZE),
                        help=f"window size in pixels, WIDTHxHEIGHT (default {DEFAULT_SIZE})")
    parser.add_argument("--tour", action="store_true",
                        help="one PNG per mission instant (start, closest approach, arrival) into OUT")
    parser.add_argument("--settle", type=float, default=3.0, help="first pause before a screenshot (s)")
    parser.add_argument("--timeout", type=float, default=None,
                        help="give up after this many seconds (default: grows with the recording's size)")
    args = parser.parse_args(argv)
    try:
        written = run(args)
    except ScreenshotError as exc:
        print(f"screenshot: {exc}", file=sys.stderr)
        return 1
    for path in written:
        print(path)
    return 0


def run(args: argparse.Namespace) -> list[Path]:
    from scenes.clock import parse_clock

    recording: Path = args.recording
    if recording.suffix == ".json":        # a run of days: its index names one recording per day
        from tools.week_index import recording_of_day

        try:
            recording = recording_of_day(recording, getattr(args, "day", None),
                                         parse_clock(args.at) if args.at else None)
        except ValueError as exc:
            raise ScreenshotError(str(exc)) from None
    if not recording.is_file():
        raise ScreenshotError(f"{recording}: no such recording file")
    store = load_store(recording)
    offset = clock_offset_s(store)
    if args.tour:
        stops = tour_stops(store)
        if not stops:
            raise ScreenshotError(f"{recording}: no mission started in this recording (no executive events)")
        args.out.mkdir(parents=True, exist_ok=True)
        shots = []
        seen: dict[str, int] = {}
        for stop in stops:
            seen[stop.mission] = seen.get(stop.mission, 0) + 1
            shots.append((stop.sim_s, args.out / f"{stop.mission}-{seen[stop.mission]}-{stop.what}-"
                                                 f"{_hhmmss(stop.sim_s)}.png"))
    else:
        try:
            at = parse_clock(args.at) if args.at else end_of(store)
        except ValueError as exc:
            raise ScreenshotError(f"--at {args.at!r}: {exc}") from None
        args.out.parent.mkdir(parents=True, exist_ok=True)
        shots = [(at, args.out)]
    budget = args.timeout if args.timeout is not None else budget_s(recording)
    viewer = Viewer(args.size)
    written: list[Path] = []
    try:
        deadline = time.monotonic() + budget
        viewer.open(recording, deadline)
        first = True
        for sim_s, out in shots:
            viewer.set_time(sim_s, offset)
            # Each shot gets the whole budget again once the file is loaded: one slow frame must not
            # starve the rest of a tour.
            viewer.shoot(out, args.settle if first else 1.0, time.monotonic() + budget)
            first = False
            written.append(out)
    finally:
        viewer.close()
    return written


if __name__ == "__main__":
    sys.exit(main())
