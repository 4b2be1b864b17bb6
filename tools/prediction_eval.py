"""How well chronav predicts people, measured on real pedestrians (ETH/UCY text files) and on
simulated days (a run's people.csv, optionally with the scene's walls and agenda).

Why in the project: the social map plans around where people will be, so the prediction is the
navigation's view of the future; this module asks the standard question of the trajectory
prediction literature (observe 8 steps = 3.2 s, predict 12 steps = 4.8 s at 0.4 s, ADE/FDE in
metres, one deterministic prediction) of the *deployed* pipeline: the observer's tracker
(``agents/lib/perception/tracking.observer_tracker``, the observer's settings) fed noisy
detections, then the social map's ``motion.predict_many`` with its deployed parameters.  Only the
horizon and step are set to the question's (``--pred`` x ``--dt``, ``--dt``): the defaults are the
deployed ones.  The constant-velocity baseline (Schöller et al. 2020, "What the constant velocity
model can teach us about pedestrian motion prediction": the last observed step repeated) is
computed in the same run from the *true* positions, so the ratio says how much the deployed
pipeline, noise included, gains or loses against the simplest honest predictor; a second baseline,
constant velocity fed the *same noisy detections* (the last two observed ones), says how much the
tracker and predictor gain over the simplest predictor given the same sensor.

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
from shapely.geometry.base import BaseGeometry

from agents.lib.perception.tracking import Detection, observer_tracker
from agents.lib.perception.walker_model import WalkerModel
from agents.lib.socialmap.motion import MotionParams
from agents.lib.socialmap.predictors import DEFAULT_PREDICTOR, ChronavPredictor, checked_prediction
from agents.lib.socialmap.predictors import predictor as lookup_predictor
from agents.lib.socialmap.types import Person
from scenes.limits import TRAJECTORY_SAMPLES


#: the two UCY sequences shipped with chronav (scenes/data/pedestrians/SOURCES.md: provenance, citation
#: and what they may be used for): the default files of ``predict evaluate``, ``predict train`` and the bench
SHIPPED_PEDESTRIANS_DIR = Path(__file__).resolve().parents[1] / "scenes" / "data" / "pedestrians"


def shipped_pedestrian_files() -> list[Path]:
    """The shipped UCY files, sorted by name (crowds_zara03.txt, uni_examples.txt)."""
    return sorted(SHIPPED_PEDESTRIANS_DIR.glob("*.txt"))


class PedestrianFileError(ValueError):
    """A pedestrian file that cannot be evaluated: the message names the file and the line."""


@dataclass(frozen=True)
class Annotations:
    """One file: ``frames`` (distinct frame numbers, ascending) and, per frame index, the people
    present and their true positions.  ``times`` (clock seconds of each frame) and ``roles`` only
    for a simulator's people.csv, whose frames are a time grid with gaps (the simulator records
    while the robot drives): a window never spans a gap there."""

    name: str
    frames: NDArray[np.float64]
    people: list[dict[int, tuple[float, float]]]     # frame index -> {person id: (x, y)}
    times: NDArray[np.float64] | None = None
    ids: tuple[str, ...] = ()                        # person id -> name (people.csv)
    roles: tuple[str, ...] = ()


@dataclass(frozen=True)
class FileResult:
    ade: float
    fde: float
    cv_ade: float
    cv_fde: float
    tracks: int
    seconds: float
    cv_det_ade: float = math.nan      # constant velocity fed the same noisy detections
    cv_det_fde: float = math.nan

    def as_json(self) -> dict[str, float | int]:
        return {"ade": round(self.ade, 4), "fde": round(self.fde, 4), "cv_ade": round(self.cv_ade, 4),
                "cv_fde": round(self.cv_fde, 4), "cv_same_detections_ade": round(self.cv_det_ade, 4),
                "cv_same_detections_fde": round(self.cv_det_fde, 4), "tracks": self.tracks}


def read_annotations(path: Path, dt: float = 0.4) -> Annotations:
    """Read ``frame  id  x  y`` lines (tabs or spaces; blank lines skipped), or a simulator's
    ``people.csv`` (header ``t,name,role,...``) resampled every ``dt`` s.  Errors name the file and
    the line, in the user's words."""
    try:
        with path.open("rb") as handle:
            if handle.read(7) == b"t,name,":
                return read_people_csv_frames(path, dt)
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


def read_people_csv_frames(path: Path, dt: float) -> Annotations:
    """A run's people.csv (read by chronav metrics' reader, same checks) on a grid of ``dt`` s from
    its first sample: frame k holds the first sample within dt/5 of t0 + k dt (the simulator samples
    every 0.1 s: a quarter of 0.4 s off the grid is another sample, not this one)."""
    from agents.lib.metrics.metrics import TrajectoryFormatError, read_people_csv

    try:
        tracks = read_people_csv(path)
    except TrajectoryFormatError as exc:
        raise PedestrianFileError(str(exc)) from None
    if len(tracks.times) == 0:
        raise PedestrianFileError(f"{path}: no samples")
    grid = (tracks.times - tracks.times[0]) / dt
    k = np.round(grid)
    on_grid = np.flatnonzero(np.abs(grid - k) < 0.2)
    frames, first = np.unique(k[on_grid], return_index=True)
    rows = on_grid[first]
    present = tracks.present          # who has a row at that time: a person who left is not there
    people = [{pid: (float(tracks.x[r, pid]), float(tracks.y[r, pid])) for pid in range(len(tracks.names))
               if present[r, pid]} for r in rows.tolist()]
    return Annotations(path.name, frames, people, tracks.times[rows], tuple(tracks.names),
                       tuple(tracks.roles) or ("resident",) * len(tracks.names))


def windows(data: Annotations, length: int) -> list[tuple[int, int]]:
    """(start frame index, person id) of every run of ``length`` consecutive frames in which the
    person is present in all of them (the standard loader's windows; on a people.csv's time grid
    consecutive means one ``dt`` apart)."""
    out: list[tuple[int, int]] = []
    present: dict[int, int] = {}    # person id -> consecutive frames present, ending at the current one
    for i, frame in enumerate(data.people):
        if data.times is not None and i > 0 and data.frames[i] != data.frames[i - 1] + 1:
            present = {}
        present = {pid: present.get(pid, 0) + 1 for pid in frame}
        out.extend((i - length + 1, pid) for pid, run in present.items() if run >= length)
    return sorted(out)


def constant_velocity(observed: NDArray[np.float64], steps: int) -> NDArray[np.float64]:
    """Schöller et al.'s CVM: the last observed step repeated ``steps`` times."""
    step = observed[-1] - observed[-2]
    return observed[-1] + step[None, :] * np.arange(1, steps + 1)[:, None]


@dataclass
class SceneContext:
    """What chronav knows beyond the tracks, for a simulator's people.csv: the scene's walls (and
    closed doors) and, with ``agenda``, the activities: the people are written into a DSR graph at
    the window's time with the building, objects and agenda, and read back as the social map reads
    them (``dsr_people``: destinations included), then predicted against the map's walls."""

    scene_path: Path
    agenda: bool = True

    def __post_init__(self) -> None:
        from agents.world.navigation import NavigationMaps
        from agents.world.scene_world import load_world

        self.world = load_world(self.scene_path)
        self.nav = NavigationMaps.for_scene(self.world.scene)

    def people_and_walls(self, t_s: float, people: list[Person]) -> tuple[list[Person], BaseGeometry | None]:
        from agents.world.dsr_readers import closed_doors, dsr_people
        from agents.world.dsr_writers import (write_activities, write_building, write_clock, write_object,
                                              write_person)
        from agents.world.timeline import agenda_at, doors_at
        from dsr import DSRGraph

        scene = self.world.scene
        graph = DSRGraph(agent="predict_evaluate")
        write_building(graph, scene, doors_at(scene, t_s))
        write_clock(graph, scene, t_s, scene.clock.rate)
        for obj in scene.objects:
            write_object(graph, obj, scene.room_at(obj.pose.x, obj.pose.y))
        for p in people:
            write_person(graph, p.name, p.role, (p.x, p.y, p.theta), scene.room_at(p.x, p.y), t_s, (p.vx, p.vy))
        if self.agenda:
            write_activities(graph, agenda_at(self.world, t_s))
        read = {p.name: p for p in dsr_people(graph)}
        return [read.get(p.name, p) for p in people], self.nav.static((), closed_doors(graph)).walls


def noisy_annotations(data: Annotations, noise: float, rng: np.random.Generator) -> list[dict[int, tuple[float, float]]]:
    """Every annotation with ``noise`` m of Gaussian noise per axis, drawn once (module doc): the
    detections the benchmark and the walker model's training (tools/train_prediction.py) feed the
    tracker."""
    return [{pid: (x + e[0], y + e[1]) for (pid, (x, y)), e in
             zip(sorted(frame.items()), rng.normal(0.0, noise, (len(frame), 2)) if noise > 0
                 else np.zeros((len(frame), 2)), strict=True)}
            for frame in data.people]


def evaluate(data: Annotations, obs: int = 8, pred: int = 12, dt: float = 0.4, noise: float = 0.0,
             seed: int = 0, motion: MotionParams | None = None, context: SceneContext | None = None,
             min_speed: float = 0.0, detect_every: int = 1, model: WalkerModel | None = None,
             predictor: str = DEFAULT_PREDICTOR) -> FileResult:
    """ADE/FDE of the deployed tracker + predictor on every window of ``data``, and of the
    constant-velocity baseline on the true positions (module doc).  ``min_speed`` > 0 keeps only
    windows whose person walked at least that fast on average over the observed steps (a simulated
    day's people mostly stand, where every predictor is right).  ``detect_every`` > 1 detects
    that many times per frame (positions interpolated linearly between the frames, each detection
    with its own noise): the observer's 10 Hz on 2.5 Hz annotations is 4.  ``model``: another walker
    model than the shipped one (a model trained on other files: cross-file figures).  ``predictor``:
    a registered people predictor (agents/lib/socialmap/predictors.py; chronav's by default)."""
    predicts = lookup_predictor(predictor)
    started = time.perf_counter()
    motion = (motion or MotionParams()).model_copy(update={"horizon_s": pred * dt, "step_s": dt})
    if context is not None and data.times is None:
        raise PedestrianFileError(f"{data.name}: --scene needs a simulator's people.csv (its clock times)")
    rng = np.random.default_rng(seed)
    noisy = noisy_annotations(data, noise, rng)
    m = max(1, int(detect_every))
    between = [rng.normal(0.0, noise, (m - 1, len(frame), 2)) if noise > 0 and m > 1
               else np.zeros((max(m - 1, 0), len(frame), 2)) for frame in data.people]
    names = data.ids or None
    times = np.arange(1, pred + 1, dtype=np.float64) * dt
    by_start: dict[int, list[int]] = {}
    for start, pid in windows(data, obs + pred):
        if min_speed > 0:
            a, b = np.array(data.people[start][pid]), np.array(data.people[start + obs - 1][pid])
            if np.hypot(*(b - a)) < min_speed * (obs - 1) * dt:
                continue
        by_start.setdefault(start, []).append(pid)
    errors, cv_errors, cv_det_errors = [], [], []
    for start, pids in by_start.items():
        tracker = observer_tracker(noise, model)
        for k in range(start, start + obs):
            tracker.update(k * dt, [Detection(names[pid] if names else str(pid), x, y, 0.0)
                                    for pid, (x, y) in sorted(noisy[k].items())])
            if k == start + obs - 1:
                break
            for j in range(1, m):      # detections between frame k and k + 1 (detect_every > 1)
                f = j / m
                tracker.update((k + f) * dt, [
                    Detection(names[pid] if names else str(pid), (1 - f) * x + f * data.people[k + 1][pid][0] + e[0],
                              (1 - f) * y + f * data.people[k + 1][pid][1] + e[1], 0.0)
                    for (pid, (x, y)), e in zip(sorted(data.people[k].items()), between[k][j - 1], strict=True)
                    if pid in data.people[k + 1]])
        now = (start + obs - 1) * dt
        people = []
        for pid in pids:
            name = names[pid] if names else str(pid)
            x, y, theta, vx, vy = tracker.estimate(name, now)
            people.append(Person(name, x, y, theta, role=data.roles[pid] if data.roles else "resident", vx=vx, vy=vy))
        walls = None
        if context is not None and data.times is not None:   # (a context without times was refused above)
            people, walls = context.people_and_walls(float(data.times[start + obs - 1]), people)
        if predictor == DEFAULT_PREDICTOR:   # chronav's, with this evaluation's motion parameters
            predicted = ChronavPredictor(motion).predict(people, times, walls)
        else:
            predicted = checked_prediction(predictor, predicts.predict(people, times, walls), len(people), pred)
        for pid, ahead in zip(pids, predicted, strict=True):
            truth = np.array([data.people[k][pid] for k in range(start, start + obs + pred)])
            future = truth[obs:]
            errors.append(np.linalg.norm(ahead - future, axis=1))
            cv_errors.append(np.linalg.norm(constant_velocity(truth[:obs], pred) - future, axis=1))
            seen = np.array([noisy[k][pid] for k in (start + obs - 2, start + obs - 1)])
            cv_det_errors.append(np.linalg.norm(constant_velocity(seen, pred) - future, axis=1))
    if not errors:
        raise PedestrianFileError(f"{data.name}: no person is present in {obs + pred} consecutive frames "
                                  f"(--obs {obs} + --pred {pred})"
                                  + (f" walking at {min_speed:g} m/s or faster" if min_speed > 0 else "")
                                  + "; nothing to evaluate")
    e, c, d = np.array(errors), np.array(cv_errors), np.array(cv_det_errors)
    return FileResult(float(e.mean()), float(e[:, -1].mean()), float(c.mean()), float(c[:, -1].mean()),
                      len(errors), time.perf_counter() - started, float(d.mean()), float(d[:, -1].mean()))


def summary(results: dict[str, FileResult]) -> dict[str, object]:
    """The ``--json`` object: per file, and the file-averaged ADE/FDE over the file-averaged baseline
    (the literature's "average over the sequences", each file counting once), for both baselines:
    constant velocity on the true positions (``*_over_cv``) and fed the same noisy detections
    (``*_over_cv_same_detections``)."""
    def mean(attr: str) -> float:
        return float(np.mean([getattr(r, attr) for r in results.values()]))

    def ratio(a: str, b: str) -> float | None:
        top, bottom = mean(a), mean(b)
        return round(top / bottom, 4) if bottom > 0 and math.isfinite(bottom) else None

    return {"files": {name: r.as_json() for name, r in results.items()},
            "ade_over_cv": ratio("ade", "cv_ade"), "fde_over_cv": ratio("fde", "cv_fde"),
            "ade_over_cv_same_detections": ratio("ade", "cv_det_ade"),
            "fde_over_cv_same_detections": ratio("fde", "cv_det_fde")}


def evaluate_files(paths: Sequence[Path], dt: float = 0.4, **options: object) -> dict[str, FileResult]:
    """Every file, read and evaluated; a bad file raises PedestrianFileError before any work."""
    datasets = [read_annotations(path, dt) for path in paths]
    names = [d.name for d in datasets]
    if len(set(names)) != len(names):
        duplicate = next(n for n in names if names.count(n) > 1)
        raise PedestrianFileError(f"{duplicate}: given twice (the report keys files by name)")
    return {d.name: evaluate(d, dt=dt, **options) for d in datasets}   # type: ignore[arg-type]
