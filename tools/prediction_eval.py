"""How well chronav predicts people, measured on real pedestrians (ETH/UCY text files).

Why in the project: the social map plans around where people will be, so the prediction is the
navigation's view of the future; this module asks the standard question of the trajectory
prediction literature (observe 8 steps = 3.2 s, predict 12 steps = 4.8 s at 0.4 s, ADE/FDE in
metres, one deterministic prediction) of the *deployed* pipeline: the observer's tracker
(``agents/lib/perception/tracking.observer_tracker``, the observer's settings) fed noisy
detections, then the social map's ``motion.predict`` with its deployed parameters.  Only the
horizon and step are set to the question's (``--pred`` x ``--dt``, ``--dt``): the defaults are the
deployed ones.  The constant-velocity baseline (Schöller et al. 2020, "What the constant velocity
model can teach us about pedestrian motion prediction": the last observed step repeated) is
computed in the same run from the *true* positions, so the ratio says how much the deployed
pipeline, noise included, gains or loses against the simplest honest predictor.

Windows are the standard loader's (Social-GAN's ``TrajectoryDataset``): the file's distinct frames
in order; every run of ``obs + pred`` consecutive frames in which a person is present in all of
them is one window.  Detection: in each observed frame every person present is detected (a
re-identifying detector names them), with Gaussian position noise ``--noise`` drawn once per
annotation (seeded), so the same detection is equally wrong in every window that contains it.
Tracking: one tracker per window start, fed the ``obs`` observed frames of everyone present (so
crossings and gating are exercised, and nothing before the window is seen, as in the protocol).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from agents.lib.perception.tracking import Detection, observer_tracker
from agents.lib.socialmap.motion import MotionParams, predict
from agents.lib.socialmap.types import Person
from scenes.limits import TRAJECTORY_SAMPLES


class PedestrianFileError(ValueError):
    """A pedestrian file that cannot be evaluated: the message names the file and the line."""


@dataclass(frozen=True)
class Annotations:
    """One ETH/UCY file: ``frames`` (distinct frame numbers, ascending) and, per frame index,
    the people present and their true positions."""

    name: str
    frames: NDArray[np.float64]
    people: list[dict[int, tuple[float, float]]]     # frame index -> {person id: (x, y)}


@dataclass(frozen=True)
class FileResult:
    ade: float
    fde: float
    cv_ade: float
    cv_fde: float
    tracks: int
    seconds: float

    def as_json(self) -> dict[str, float | int]:
        return {"ade": round(self.ade, 4), "fde": round(self.fde, 4), "cv_ade": round(self.cv_ade, 4),
                "cv_fde": round(self.cv_fde, 4), "tracks": self.tracks}


def read_annotations(path: Path) -> Annotations:
    """Read ``frame  id  x  y`` lines (tabs or spaces; blank lines skipped).  Errors name the file
    and the line, in the user's words."""
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise PedestrianFileError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise PedestrianFileError(f"{path}: cannot be read as text ({exc.__class__.__name__})") from None
    limit = TRAJECTORY_SAMPLES.value()
    rows: dict[tuple[float, int], tuple[float, float]] = {}
    for number, line in enumerate(text.splitlines(), start=1):
        fields = line.split()
        if not fields:
            continue
        if len(rows) >= limit:
            raise PedestrianFileError(f"{path}:{number}: more than {limit} annotations "
                                      f"(raise CHRONAV_LIMIT_TRAJECTORY_SAMPLES to read it)")
        if len(fields) != 4:
            raise PedestrianFileError(f"{path}:{number}: expected 4 columns 'frame id x y', found {len(fields)}")
        try:
            frame, pid, x, y = (float(f) for f in fields)
        except ValueError:
            raise PedestrianFileError(f"{path}:{number}: 'frame id x y' must be numbers, got {line.strip()!r}") \
                from None
        if not all(math.isfinite(v) for v in (frame, pid, x, y)):
            raise PedestrianFileError(f"{path}:{number}: a value is not a finite number: {line.strip()!r}")
        if pid != int(pid):
            raise PedestrianFileError(f"{path}:{number}: person id {fields[1]} is not a whole number")
        key = (frame, int(pid))
        if key in rows:
            raise PedestrianFileError(f"{path}:{number}: person {int(pid)} appears twice in frame {fields[0]}")
        rows[key] = (x, y)
    if not rows:
        raise PedestrianFileError(f"{path}: no annotations (expected lines 'frame id x y')")
    frames = np.unique(np.array([f for f, _ in rows]))
    index = {float(f): i for i, f in enumerate(frames)}
    people: list[dict[int, tuple[float, float]]] = [{} for _ in frames]
    for (frame, pid), xy in rows.items():
        people[index[frame]][pid] = xy
    return Annotations(path.name, frames, people)


def windows(data: Annotations, length: int) -> list[tuple[int, int]]:
    """(start frame index, person id) of every run of ``length`` consecutive frames in which the
    person is present in all of them (the standard loader's windows)."""
    out = []
    present: dict[int, int] = {}    # person id -> consecutive frames present, ending at the current one
    for i, frame in enumerate(data.people):
        present = {pid: present.get(pid, 0) + 1 for pid in frame}
        out.extend((i - length + 1, pid) for pid, run in present.items() if run >= length)
    return sorted(out)


def constant_velocity(observed: NDArray[np.float64], steps: int) -> NDArray[np.float64]:
    """Schöller et al.'s CVM: the last observed step repeated ``steps`` times."""
    step = observed[-1] - observed[-2]
    return observed[-1] + step[None, :] * np.arange(1, steps + 1)[:, None]


def predicted_positions(person: Person, motion: MotionParams, times: NDArray[np.float64]) -> NDArray[np.float64]:
    """The social map's prediction at ``times`` (s ahead): where ``predict`` says nothing (a standing
    person) or stops short (a wall, an arrival) the person stays at their last predicted place."""
    here = np.array([[person.x, person.y]])
    found = predict(person, motion, None)
    if found is None or len(found.times) == 0:
        return np.repeat(here, len(times), axis=0)
    known_t = np.concatenate([[0.0], found.times])
    known = np.concatenate([here, found.points])
    return np.stack([np.interp(times, known_t, known[:, 0]), np.interp(times, known_t, known[:, 1])], axis=1)


def evaluate(data: Annotations, obs: int = 8, pred: int = 12, dt: float = 0.4, noise: float = 0.0,
             seed: int = 0, motion: MotionParams | None = None) -> FileResult:
    """ADE/FDE of the deployed tracker + predictor on every window of ``data``, and of the
    constant-velocity baseline on the true positions (module doc)."""
    started = time.perf_counter()
    motion = (motion or MotionParams()).model_copy(update={"horizon_s": pred * dt, "step_s": dt})
    rng = np.random.default_rng(seed)
    noisy = [{pid: (x + e[0], y + e[1]) for (pid, (x, y)), e in
              zip(sorted(frame.items()), rng.normal(0.0, noise, (len(frame), 2)) if noise > 0
                  else np.zeros((len(frame), 2)), strict=True)}
             for frame in data.people]
    times = np.arange(1, pred + 1) * dt
    by_start: dict[int, list[int]] = {}
    for start, pid in windows(data, obs + pred):
        by_start.setdefault(start, []).append(pid)
    errors, cv_errors = [], []
    for start, pids in by_start.items():
        tracker = observer_tracker(noise)
        for k in range(start, start + obs):
            tracker.update(k * dt, [Detection(str(pid), x, y, 0.0) for pid, (x, y) in sorted(noisy[k].items())])
        now = (start + obs - 1) * dt
        for pid in pids:
            truth = np.array([data.people[k][pid] for k in range(start, start + obs + pred)])
            future = truth[obs:]
            x, y, theta, vx, vy = tracker.estimate(str(pid), now)
            guess = predicted_positions(Person(str(pid), x, y, theta, vx=vx, vy=vy), motion, times)
            errors.append(np.linalg.norm(guess - future, axis=1))
            cv_errors.append(np.linalg.norm(constant_velocity(truth[:obs], pred) - future, axis=1))
    if not errors:
        raise PedestrianFileError(f"{data.name}: no person is present in {obs + pred} consecutive frames "
                                  f"(--obs {obs} + --pred {pred}); nothing to evaluate")
    e, c = np.array(errors), np.array(cv_errors)
    return FileResult(float(e.mean()), float(e[:, -1].mean()), float(c.mean()), float(c[:, -1].mean()),
                      len(errors), time.perf_counter() - started)


def summary(results: dict[str, FileResult]) -> dict[str, object]:
    """The ``--json`` object: per file, and the file-averaged ADE/FDE over the file-averaged baseline
    (the literature's "average over the sequences", each file counting once)."""
    ade = np.mean([r.ade for r in results.values()])
    fde = np.mean([r.fde for r in results.values()])
    cv_ade = np.mean([r.cv_ade for r in results.values()])
    cv_fde = np.mean([r.cv_fde for r in results.values()])
    return {"files": {name: r.as_json() for name, r in results.items()},
            "ade_over_cv": round(float(ade / cv_ade), 4) if cv_ade > 0 else None,
            "fde_over_cv": round(float(fde / cv_fde), 4) if cv_fde > 0 else None}


def evaluate_files(paths: Sequence[Path], **options: float | int) -> dict[str, FileResult]:
    """Every file, read and evaluated; a bad file raises PedestrianFileError before any work."""
    datasets = [read_annotations(path) for path in paths]
    names = [d.name for d in datasets]
    if len(set(names)) != len(names):
        duplicate = next(n for n in names if names.count(n) > 1)
        raise PedestrianFileError(f"{duplicate}: given twice (the report keys files by name)")
    return {d.name: evaluate(d, **options) for d in datasets}   # type: ignore[arg-type]
