"""Recorded pedestrians (ETH/UCY text: ``frame  id  x  y`` a line): read strictly, one track a person.

Why strict here when ``chronav predict evaluate`` only needs windows: a scene replays every person
along their record, entering when it starts and leaving when it ends (``routine: replay``), so a
file that says two things about one person at one frame, goes back in time, or has a person leave
and come back is ambiguous about who is where; each is refused with the file and the line, in the
user's words.  The same reader serves ``chronav scene from-crowd`` (the plaza and the missions),
the scene check and the simulator (the replayed people), so all three see the same tracks.

Times: the file's frames are a grid (ETH/UCY: 10 frames apart = 0.4 s, 2.5 Hz); the smallest step
between two distinct frames is one ``dt`` (default 0.4 s), and a track's times are seconds since
the file's first frame.  A person is present from their first to their last annotation; they must
be annotated at every distinct frame of the file in between (the standard loaders' assumption),
else they "reappeared after leaving".
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from scenes.limits import CROWD_PEOPLE, CROWD_ROWS

#: seconds between two annotated frames of the ETH/UCY releases (frames 10 apart at 25 fps)
DEFAULT_FRAME_DT_S = 0.4


class RecordingError(ValueError):
    """A recording that cannot be replayed: the message names the file and the line."""


@dataclass(frozen=True)
class Track:
    """One recorded person: times (s since the recording's first frame, ascending) and positions."""

    id: int
    t: NDArray[np.float64]
    xy: NDArray[np.float64]            # (n, 2), metres
    first_line: int                    # where the person first appears in the file (for errors)

    @property
    def start_s(self) -> float:
        return float(self.t[0])

    @property
    def end_s(self) -> float:
        return float(self.t[-1])

    def at(self, t_s: float) -> tuple[float, float, float, float]:
        """Position and velocity at ``t_s`` (s since the recording's start), linearly interpolated
        between annotations; clamped to the ends (velocity 0 outside the record)."""
        t, xy = self.t, self.xy
        if len(t) == 1 or t_s <= t[0] or t_s >= t[-1]:
            x, y = xy[0] if t_s <= t[0] else xy[-1]
            return float(x), float(y), 0.0, 0.0
        k = int(np.searchsorted(t, t_s, side="right")) - 1
        f = (t_s - t[k]) / (t[k + 1] - t[k])
        v = (xy[k + 1] - xy[k]) / (t[k + 1] - t[k])
        p = xy[k] + f * (xy[k + 1] - xy[k])
        return float(p[0]), float(p[1]), float(v[0]), float(v[1])


@dataclass(frozen=True)
class Recording:
    """A file's tracks by person id, its frame step and duration."""

    path: Path
    tracks: dict[int, Track]
    dt_s: float
    duration_s: float
    rows: int

    def extent(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of every annotation."""
        xy = np.concatenate([t.xy for t in self.tracks.values()])
        return float(xy[:, 0].min()), float(xy[:, 1].min()), float(xy[:, 0].max()), float(xy[:, 1].max())


def read_recording(path: Path, dt_s: float = DEFAULT_FRAME_DT_S) -> Recording:
    """Read and check an ETH/UCY file (module doc); RecordingError names the file and the line."""
    if not (math.isfinite(dt_s) and dt_s > 0):
        raise RecordingError(f"{path}: the time step must be a positive number of seconds, got {dt_s}")
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise RecordingError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise RecordingError(f"{path}: cannot be read as text ({exc.__class__.__name__})") from None
    max_rows, max_people = CROWD_ROWS.value(), CROWD_PEOPLE.value()
    frames: list[float] = []
    ids: list[int] = []
    xs: list[float] = []
    ys: list[float] = []
    lines: list[int] = []
    seen: set[tuple[float, int]] = set()
    first_line: dict[int, int] = {}
    last_frame = -math.inf
    for number, line in enumerate(text.splitlines(), start=1):
        fields = line.split()
        if not fields or fields[0].startswith("#"):
            continue
        if len(frames) >= max_rows:
            raise RecordingError(f"{path}:{number}: more than {max_rows} annotations "
                                 f"(raise {CROWD_ROWS.env} to read it; docs/limits.md)")
        if len(fields) != 4:
            raise RecordingError(f"{path}:{number}: expected 4 columns 'frame id x y', found {len(fields)}")
        try:
            frame, pid, x, y = (float(f) for f in fields)
        except ValueError:
            raise RecordingError(f"{path}:{number}: 'frame id x y' must be numbers, got {line.strip()!r}") from None
        if not all(math.isfinite(v) for v in (frame, pid, x, y)):
            raise RecordingError(f"{path}:{number}: a value is not a finite number: {line.strip()!r}")
        if pid != int(pid) or frame != int(frame):
            raise RecordingError(f"{path}:{number}: frame and person id must be whole numbers, got {line.strip()!r}")
        if frame < last_frame:
            raise RecordingError(f"{path}:{number}: frame {fields[0]} comes after frame {last_frame:g}: "
                                 "frames must be in order (sort the file by frame)")
        key = (frame, int(pid))
        if key in seen:
            raise RecordingError(f"{path}:{number}: person {int(pid)} appears twice in frame {fields[0]}")
        seen.add(key)
        if int(pid) not in first_line:
            if len(first_line) >= max_people:
                raise RecordingError(f"{path}:{number}: more than {max_people} people "
                                     f"(raise {CROWD_PEOPLE.env} to read it; docs/limits.md)")
            first_line[int(pid)] = number
        last_frame = frame
        frames.append(frame)
        ids.append(int(pid))
        xs.append(x)
        ys.append(y)
        lines.append(number)
    if not frames:
        raise RecordingError(f"{path}: no annotations (expected lines 'frame id x y')")
    f = np.array(frames)
    distinct = np.unique(f)
    step = float(np.min(np.diff(distinct))) if len(distinct) > 1 else 1.0
    index = np.searchsorted(distinct, f)
    order = np.argsort(np.array(ids), kind="stable")
    tracks: dict[int, Track] = {}
    pid_sorted = np.array(ids)[order]
    cuts = np.flatnonzero(np.diff(pid_sorted)) + 1
    for group in np.split(order, cuts):
        pid = ids[int(group[0])]
        k = index[group]
        gaps = np.flatnonzero(np.diff(k) > 1)
        if len(gaps):
            at = int(group[gaps[0] + 1])
            raise RecordingError(f"{path}:{lines[at]}: person {pid} reappears at frame {frames[at]:g} after leaving "
                                 f"at frame {frames[int(group[gaps[0]])]:g}: a person is present once, from their "
                                 "first frame to their last (give the return a new id)")
        t = (f[group] - distinct[0]) / step * dt_s
        tracks[pid] = Track(pid, t, np.stack([np.array(xs)[group], np.array(ys)[group]], axis=1), first_line[pid])
    duration = float((distinct[-1] - distinct[0]) / step * dt_s)
    return Recording(path, tracks, dt_s, duration, len(frames))
