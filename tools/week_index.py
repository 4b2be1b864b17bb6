"""A long run's files: one recording and one run directory per day, an index that opens them as one
run, retention, and writes that never leave half a file.

Why an index and not one big recording: a week of center_day's crowd is ~80 MB of recording and
7 x 4 MB of people.csv; one file per day can be kept, copied or deleted by the day
(``--keep-days``), and the viewer opens the days it is given.  ``index.json`` (next to the days)
lists each day: its date, its offset on the week clock (week seconds, scenes/days.py), its
recording and run directory (relative to the index) and what became of it (``ok``, ``failed``,
``refused`` with the reason, ``removed`` by retention).  ``python -m tools.screenshot index.json
OUT.png --day 2 --at 11:15`` and ``rerun $(python -m tools.week_index INDEX)`` open it.

Why temp + rename: a disk that fills while a day rotates must leave the previous index (or none),
never a truncated one; :func:`write_atomic` writes a temporary file beside the target, fsyncs it
and renames it over the target, removing the temporary file if anything fails.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

INDEX_NAME = "index.json"
INDEX_KIND = "chronav-long-run-index"


class RotationError(RuntimeError):
    """A long run could not write its next file (typically: the disk is full); the run ends cleanly."""


def write_atomic(path: Path, text: str) -> None:
    """``text`` into ``path`` whole or not at all (temp file in the same folder, fsync, rename)."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as out:
            out.write(text)
            out.flush()
            os.fsync(out.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        full = exc.errno in (errno.ENOSPC, errno.EDQUOT)
        why = "the disk is full" if full else (exc.strerror or str(exc))
        raise RotationError(f"cannot write {path}: {why}; nothing half-written was left (free space, or set "
                            "CHRONAV_RUNS to a larger disk, and start the run again)") from None


def write_json(path: Path, data: Any) -> None:
    write_atomic(path, json.dumps(data, indent=2, default=str))


def tree_bytes(*paths: Path | None) -> int:
    """Bytes of the files under ``paths`` (files or folders; missing ones count 0)."""
    total = 0
    for path in paths:
        if path is None or not path.exists():
            continue
        if path.is_file():
            total += path.stat().st_size
            continue
        for root, _dirs, files in os.walk(path):
            for name in files:
                try:
                    total += (Path(root) / name).stat().st_size
                except OSError:
                    pass
    return total


def relative(path: Path | None, base: Path) -> str | None:
    if path is None:
        return None
    try:
        return str(path.resolve().relative_to(base.resolve()))
    except ValueError:
        return str(path.resolve())


def apply_retention(entries: list[dict[str, Any]], base: Path, keep_days: int | None) -> list[int]:
    """Delete the files of all but the newest ``keep_days`` days that have files; mark them removed.

    The day's accounting stays in the index and in result.json: only its recording and run
    directory go.  Returns the day numbers removed now."""
    if keep_days is None:
        return []
    with_files = [e for e in entries if e.get("rrd") or e.get("run_dir") or e.get("hours")]
    removed: list[int] = []
    for entry in with_files[:max(0, len(with_files) - keep_days)]:
        files = [entry.get("rrd"), entry.get("run_dir"), *(h.get("rrd") for h in entry.get("hours") or [])]
        for value in files:
            if value:
                target = base / value
                if target.is_dir():
                    shutil.rmtree(target, ignore_errors=True)
                else:
                    target.unlink(missing_ok=True)
        entry.update(rrd=None, run_dir=None)
        if entry.get("hours"):
            entry["hours"] = []
        entry["removed"] = True
        removed.append(int(entry["day"]))
    return removed


def read_index(path: Path) -> dict[str, Any]:
    """A long run's index, checked enough to open; ValueError in the user's words otherwise."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ValueError(f"{path}: not a readable index of a long run ({exc})") from None
    if not isinstance(data, dict) or data.get("kind") != INDEX_KIND or not isinstance(data.get("entries"), list):
        raise ValueError(f"{path}: not an index of a long run (expected \"kind\": \"{INDEX_KIND}\" and \"entries\")")
    return data


def day_recordings(index_path: Path) -> list[tuple[int, float, Path]]:
    """(day, start_s, recording) of every recording the index still has, in order: one per day, or
    one per hour of a real-time day (``hours``: its start on the day's clock)."""
    data = read_index(index_path)
    base = index_path.parent
    found: list[tuple[int, float, Path]] = []
    for entry in data["entries"]:
        parts = [(0.0, entry["rrd"])] if entry.get("rrd") else [
            (float(h.get("start_s", 0.0)), h["rrd"]) for h in entry.get("hours") or [] if h.get("rrd")]
        found += [(int(entry["day"]), start, base / rrd) for start, rrd in parts if (base / rrd).is_file()]
    return found


def recording_of_day(index_path: Path, day: int | None, at_s: float | None = None) -> Path:
    """The recording of ``day`` (1-based; None: the last day that has one) in an index; of a day
    recorded hour by hour, the hour holding ``at_s`` (seconds of that day's clock; None: the last)."""
    found = day_recordings(index_path)
    if not found:
        raise ValueError(f"{index_path}: no day of this run has a recording (removed by --keep-days, or not recorded)")
    number = found[-1][0] if day is None else day
    ofday = [(start, path) for n, start, path in found if n == number]
    if not ofday:
        raise ValueError(f"{index_path}: day {day} has no recording; days with one: "
                         f"{', '.join(str(n) for n in sorted({n for n, _, _ in found}))}")
    before = [path for start, path in ofday if at_s is None or start <= at_s]
    return before[-1] if before else ofday[0][1]


def main(argv: list[str] | None = None) -> int:
    """``python -m tools.week_index INDEX``: the day recordings, one path a line (``rerun $(...)``)."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print("usage: python -m tools.week_index INDEX.json", file=sys.stderr)
        return 2
    try:
        for _, _, path in day_recordings(Path(args[0])):
            print(path)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
