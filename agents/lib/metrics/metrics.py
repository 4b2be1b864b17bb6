"""Navigation quality metrics of a recorded trajectory: the seed's Tables 1, 2 and 4, and (with the
people's trajectories) the metrics among moving people of dynamic_metrics.py.

Every metric's name, unit, source and definition is in metric_catalog.py (and docs/metrics.md).

Why one entry point (`compute_metrics`): the CLI (`chronav metrics SCENE TRAJ.csv`), the gain tuner
and the tests must all measure a run the same way, so the definitions live here and nowhere else.

Definitions (all on the piecewise-linear path through the recorded samples):

* ``d_t`` (m): sum of the straight segment lengths between consecutive samples.
* ``tau`` (s): ``t[-1] - t[0]``.
* ``CHC`` (rad): cumulative heading change, ``sum_k |wrap(theta[k+1] - theta[k])|`` with ``wrap``
  mapping to ``[-pi, pi)``. It uses the recorded robot heading (the ``theta`` column), not the
  direction of travel, so an omnidirectional robot that strafes without turning scores 0 and a
  robot turning on the spot is counted. It is the discrete form of the seed's Eq. 18.
* ``d_min`` (m): for each person, the smallest distance from the path to the person's (x, y); for
  each object, the smallest distance from the path to the object's footprint (0 if the path
  touches or crosses it).
* ``Psi`` (%): share of the **path length** inside each exclusive proxemic band: intimate;
  personal minus intimate; social minus personal and intimate; public is the rest. Also, for each
  object, the share of the path length inside its interaction space (these may overlap each
  other, so they need not sum to 100).

Why Psi is by path length and not by time: it then describes where the path goes, independent of
the speed profile and of the sampling rate, so a slow social planner and a fast baseline are
compared on the same footing (the seed's tables report it next to ``d_t``, as a share of the path).
The price is that a robot standing still inside a zone adds nothing; ``tau`` and ``d_min`` show
that case. A run that never moves (zero length) is classified by its first sample: 100 % in the
band that contains it.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict
from shapely.geometry.base import BaseGeometry

from agents.lib.metrics.dynamic_metrics import (PERSON_RADIUS_M, DynamicMetrics, PeopleTracks, dynamic_metrics,
                                                  tracks_from_rows)
from agents.lib.metrics.metric_catalog import CATALOG, column_label
from scenes.angles import wrap_angle
from scenes.limits import TRAJECTORY_SAMPLES
from scenes.yamlio import SourceError, read_text_file

FloatArray = NDArray[np.float64]

ZONE_NAMES: tuple[str, ...] = ("intimate", "personal", "social")
PSI_BANDS: tuple[str, ...] = ("intimate", "personal", "social", "public")
TRAJECTORY_HEADER: tuple[str, ...] = ("t", "x", "y", "theta")
# A trajectory's times are seconds on the sim clock (since midnight, up to the end of the next day)
# or relative to its start; anything beyond is a unit mistake (ms, epoch seconds) or garbage.
MAX_TRAJECTORY_TIME_S = 2 * 86400.0
# Positions are metres in a building's frame; farther than this is not a building.
MAX_COORDINATE_M = 100_000.0


class MetricsInputError(ValueError):
    """Bad trajectory or scene input; the message names the argument, key or sample."""


class TrajectoryFormatError(MetricsInputError):
    """A trajectory CSV file that cannot be read; the message names the file and line."""


NO_PEOPLE = "no people's trajectories: no people.csv beside the trajectory, give --people"


class MetricsReport(BaseModel):
    """Everything measured of one run, ``--definitions published``.  ``model_dump()`` gives the JSON;
    each key's label, unit, source and definition: metric_catalog.py."""

    model_config = ConfigDict(frozen=True)

    samples: int
    distance_travelled_m: float
    duration_s: float
    cumulative_heading_change_rad: float
    d_min_person_m: dict[str, float]
    d_min_object_m: dict[str, float]
    psi_zone_percent: dict[str, float]
    psi_unadapted_zone_percent: dict[str, float] = {}   # only when the wall adaptation changed a space
    psi_object_percent: dict[str, float]
    psi_basis: str = "path_length"
    dynamic: DynamicMetrics | None = None     # among the moving people, when their trajectories are known
    missing: dict[str, str] = {}              # metric key -> why it has no value

    def to_table(self) -> list[tuple[str, str]]:
        """(metric with unit, value) rows in the catalogue's order, ready to print; a metric without a
        value says why.  One row per metric: each label is used once (metric_catalog.py)."""
        values = flatten(self.model_dump())
        missing = dict(self.missing)
        if self.dynamic is not None:
            missing.update({f"dynamic.{key}": why for key, why in self.dynamic.missing.items()})
        rows: list[tuple[str, str]] = []
        for metric in CATALOG:
            if metric.key.startswith("dynamic.") and self.dynamic is None:
                continue
            if metric.key.endswith(".*"):       # one row per person / object / band (not the nested ones)
                prefix = metric.key[:-1]
                if prefix.count(".") == 1:
                    rows += [(column_label(column), _fmt(value, metric.unit)) for column, value in values.items()
                             if column.startswith(prefix) and "." not in column[len(prefix):]]
            elif metric.key in values:
                rows.append((column_label(metric.key), _fmt(values[metric.key], metric.unit)))
            elif metric.key in missing:
                rows.append((column_label(metric.key), f"- ({missing[metric.key]})"))
        if self.dynamic is None:
            rows.append(("metrics among moving people", f"- ({self.missing.get('dynamic', NO_PEOPLE)})"))
        return rows


def flatten(metrics: Mapping[str, object], prefix: str = "") -> dict[str, float]:
    """Every number of a report as ``dotted.key -> float`` (texts and Nones are skipped)."""
    out: dict[str, float] = {}
    for key, value in metrics.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            out.update(flatten(value, f"{name}."))
        elif isinstance(value, bool | int | float):
            out[name] = float(value)
    return out


def _fmt(value: float, unit: str) -> str:
    if unit == "count":
        return str(int(value))
    if unit == "yes/no":
        return "yes" if value else "no"
    if unit.startswith("%"):
        return f"{value:.1f}"
    return f"{value:.3f}" if abs(value) < 10 else f"{value:.2f}"


def compute_metrics(
    trajectory: ArrayLike,
    people: Mapping[str, tuple[float, float]] | None = None,
    objects: Mapping[str, BaseGeometry] | None = None,
    zones: Mapping[str, BaseGeometry | None] | None = None,
    interaction_spaces: Mapping[str, BaseGeometry] | None = None,
    people_tracks: PeopleTracks | None = None,
    robot_radius_m: float = 0.3,
    obstacles: BaseGeometry | None = None,
    *,
    unadapted_zones: Mapping[str, BaseGeometry | None] | None = None,
    goal_xy: tuple[float, float] | None = None,
    person_radius_m: float = PERSON_RADIUS_M,
) -> MetricsReport:
    """Measure one run: the seed's tables and, with ``people_tracks``, the metrics among moving people.

    ``trajectory``: (N, 4) rows of (t [s], x [m], y [m], theta [rad]), time non-decreasing.
    ``people``: name -> (x, y). ``objects``: name -> footprint geometry. ``zones``: any of
    "intimate", "personal", "social" -> (multi)polygon of that contour (missing or None = empty), as
    the planner used them (adapted to walls when adaptation is on); ``unadapted_zones`` the same
    without the adaptation (Psi beside it, named so).  ``interaction_spaces``: object name -> polygon.
    ``people_tracks``: every person's trajectory (people.csv); ``robot_radius_m``,
    ``person_radius_m``, ``obstacles`` (walls and footprints) and ``goal_xy`` (the target) go with it
    (dynamic_metrics.py).
    """
    traj = validate_trajectory(trajectory)
    zone_geoms = _validate_zones(zones or {})
    people = dict(people or {})
    objects = dict(objects or {})
    interaction_spaces = dict(interaction_spaces or {})
    _check_geometries("objects", objects)
    _check_geometries("interaction_spaces", interaction_spaces)
    path = path_geometry(traj)
    return MetricsReport(
        samples=int(traj.shape[0]),
        distance_travelled_m=distance_travelled(traj),
        duration_s=float(traj[-1, 0] - traj[0, 0]),
        cumulative_heading_change_rad=cumulative_heading_change(traj),
        d_min_person_m={name: _person_distance(path, name, pos) for name, pos in people.items()},
        d_min_object_m={name: float(path.distance(geom)) for name, geom in objects.items()},
        psi_zone_percent=psi_zone_percent(path, zone_geoms),
        psi_unadapted_zone_percent={} if unadapted_zones is None else
        psi_zone_percent(path, _validate_zones(unadapted_zones)),
        psi_object_percent={name: _share_inside(path, geom) for name, geom in interaction_spaces.items()},
        dynamic=None if people_tracks is None else dynamic_metrics(
            traj, people_tracks, robot_radius_m, obstacles, person_radius_m=person_radius_m, goal_xy=goal_xy),
        missing={} if people_tracks is not None else {"dynamic": NO_PEOPLE},
    )


def validate_trajectory(trajectory: ArrayLike) -> FloatArray:
    """Return the trajectory as a float (N, 4) array or raise MetricsInputError naming the sample."""
    try:
        traj = np.asarray(trajectory, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise MetricsInputError(f"trajectory: not numeric ({exc})") from exc
    if traj.ndim != 2 or traj.shape[1] != 4:
        raise MetricsInputError(f"trajectory: expected shape (N, 4) of t,x,y,theta, got {traj.shape}")
    if traj.shape[0] == 0:
        raise MetricsInputError("trajectory: no samples")
    bad = np.flatnonzero(~np.isfinite(traj).all(axis=1))
    if bad.size:
        raise MetricsInputError(f"trajectory: sample {int(bad[0])} is not finite: {traj[bad[0]].tolist()}")
    back = np.flatnonzero(np.diff(traj[:, 0]) < 0)
    if back.size:
        k = int(back[0]) + 1
        raise MetricsInputError(f"trajectory: time goes backwards at sample {k} "
                                f"({traj[k - 1, 0]} -> {traj[k, 0]})")
    return traj


def path_geometry(traj: FloatArray) -> BaseGeometry:
    """The driven path as a LineString (a Point when the robot never moved)."""
    xy = traj[:, 1:3]
    keep = np.ones(len(xy), dtype=bool)
    keep[1:] = np.any(np.diff(xy, axis=0) != 0.0, axis=1)
    xy = xy[keep]
    if len(xy) < 2:
        return shapely.Point(xy[0])
    return shapely.LineString(xy)


def distance_travelled(traj: FloatArray) -> float:
    """d_t: length of the polyline through the samples (m)."""
    return float(np.hypot(*np.diff(traj[:, 1:3], axis=0).T).sum()) if len(traj) > 1 else 0.0


def cumulative_heading_change(traj: FloatArray) -> float:
    """CHC: sum of |heading change| between consecutive samples, each wrapped to [-pi, pi) (rad)."""
    if len(traj) < 2:
        return 0.0
    dtheta = np.diff(traj[:, 3])
    wrapped = wrap_angle(dtheta)
    return float(np.abs(wrapped).sum())


def psi_zone_percent(path: BaseGeometry, zones: Mapping[str, BaseGeometry]) -> dict[str, float]:
    """Share (%) of the path in the exclusive bands intimate / personal / social / public."""
    empty = shapely.Polygon()
    intimate = zones.get("intimate", empty)
    personal = shapely.difference(zones.get("personal", empty), intimate)
    inner = shapely.union(intimate, zones.get("personal", empty))
    social = shapely.difference(zones.get("social", empty), inner)
    shares = {"intimate": _share_inside(path, intimate),
              "personal": _share_inside(path, personal),
              "social": _share_inside(path, social)}
    shares["public"] = max(0.0, 100.0 - sum(shares.values()))
    return shares


def _share_inside(path: BaseGeometry, area: BaseGeometry) -> float:
    """Percentage of ``path``'s length inside ``area`` (a point path counts 0 or 100)."""
    if area.is_empty:
        return 0.0
    if path.geom_type == "Point":
        return 100.0 if area.covers(path) else 0.0
    return 100.0 * float(path.intersection(area).length) / float(path.length)


def _person_distance(path: BaseGeometry, name: str, pos: tuple[float, float]) -> float:
    try:
        x, y = (float(v) for v in pos)
    except (TypeError, ValueError) as exc:
        raise MetricsInputError(f"people[{name!r}]: expected (x, y), got {pos!r}") from exc
    if not (math.isfinite(x) and math.isfinite(y)):
        raise MetricsInputError(f"people[{name!r}]: position is not finite: {pos!r}")
    return float(path.distance(shapely.Point(x, y)))


def _validate_zones(zones: Mapping[str, BaseGeometry | None]) -> dict[str, BaseGeometry]:
    out: dict[str, BaseGeometry] = {}
    for key, geom in zones.items():
        if key not in ZONE_NAMES:
            raise MetricsInputError(f"zones: unknown key {key!r}; expected some of {list(ZONE_NAMES)}")
        if geom is None:
            continue
        _check_geometries("zones", {key: geom})
        out[key] = geom
    return out


def _check_geometries(argument: str, geoms: Mapping[str, object]) -> None:
    for name, geom in geoms.items():
        if not isinstance(geom, BaseGeometry):
            raise MetricsInputError(f"{argument}[{name!r}]: expected a shapely geometry, "
                                    f"got {type(geom).__name__}")
        if not geom.is_empty and not geom.is_valid:
            raise MetricsInputError(f"{argument}[{name!r}]: invalid geometry "
                                    f"({shapely.is_valid_reason(geom)})")


def _csv_rows(path: Path, text: str) -> Iterator[tuple[int, list[str]]]:
    """(line number, cells) of each CSV line; the csv module's own refusals (a cell over its
    131,072-character limit, a NUL byte) as located errors instead of a ``_csv.Error`` traceback."""
    reader = csv.reader(text.splitlines())
    lineno = 0
    while True:
        try:
            fields = next(reader)
        except StopIteration:
            return
        except csv.Error as exc:
            detail = (f"a cell of more than {csv.field_size_limit():,} characters; cells are numbers"
                      if "field limit" in str(exc) else f"not CSV ({str(exc)[:100]})")
            raise TrajectoryFormatError(f"{path}:{reader.line_num}: {detail}") from None
        lineno = reader.line_num
        yield lineno, fields


def _csv_records(path: Path, header: tuple[str, ...], what: str, max_rows: int) -> Iterator[tuple[int, list[str]]]:
    """(line number, stripped cells) of each row of a CSV after its header, blank lines skipped.

    Why one reader for trajectory.csv and people.csv: the same bounded read, header and column
    checks and the same located messages (``FILE:LINE: ...``) for both files a user hands in."""
    try:
        text = read_text_file(path, max_bytes=max_rows * 128, limit_env=TRAJECTORY_SAMPLES.env,
                              what=what)  # a UTF-8 byte-order mark is dropped
    except SourceError as exc:
        raise TrajectoryFormatError(str(exc)) from None
    names = ",".join(header)
    header_seen = False
    count = 0
    for lineno, fields in _csv_rows(path, text):
        if not fields or all(not f.strip() for f in fields):
            continue
        cells = [f.strip() for f in fields]
        if not header_seen:
            if tuple(c.lower() for c in cells) != header:
                raise TrajectoryFormatError(f"{path}:{lineno}: expected header '{names}', "
                                            f"got {cell_text(','.join(cells))!r}")
            header_seen = True
            continue
        if len(cells) != len(header):
            raise TrajectoryFormatError(f"{path}:{lineno}: expected {len(header)} values ({names}), "
                                        f"got {len(cells)}")
        count += 1
        if count > max_rows:
            raise TrajectoryFormatError(f"{path}:{lineno}: more than {max_rows:,} rows ({TRAJECTORY_SAMPLES.env})")
        yield lineno, cells
    if not header_seen:
        raise TrajectoryFormatError(f"{path}:1: empty file, expected header '{names}'")


def _numbers(path: Path, lineno: int, columns: Sequence[str], cells: Sequence[str]) -> list[float]:
    """The cells as finite floats, or a located error naming the column."""
    values: list[float] = []
    for column, cell in zip(columns, cells, strict=True):
        try:
            value = float(cell)
        except ValueError:
            raise TrajectoryFormatError(f"{path}:{lineno}: column {column!r}: {cell_text(cell)!r} is not a number") \
                from None
        if not math.isfinite(value):
            raise TrajectoryFormatError(f"{path}:{lineno}: column {column!r}: {cell_text(cell)!r} is not finite")
        values.append(value)
    return values


def _check_sample(path: Path, lineno: int, txy: Sequence[float], cells: Sequence[str], last_t: float) -> None:
    """A sample's time ``txy[0]`` is of the simulated day and not before the previous one; its
    position ``txy[1:3]`` is near the origin.  ``cells`` are the same three as written (messages
    quote what the user wrote)."""
    t, x, y = txy[:3]
    if not 0.0 <= t <= MAX_TRAJECTORY_TIME_S:
        raise TrajectoryFormatError(f"{path}:{lineno}: column 't': {cell_text(cells[0])} s is not a time of the "
                                    f"simulated day (0 to {MAX_TRAJECTORY_TIME_S:,.0f} s, i.e. up to 48:00)")
    if max(abs(x), abs(y)) > MAX_COORDINATE_M:
        raise TrajectoryFormatError(f"{path}:{lineno}: position ({cell_text(cells[1])}, {cell_text(cells[2])}) is more than "
                                    f"{MAX_COORDINATE_M:,.0f} m from the origin; positions are metres in the "
                                    "scene's frame")
    if t < last_t:
        raise TrajectoryFormatError(f"{path}:{lineno}: time goes backwards ({last_t} -> {t})")


def read_trajectory_csv(path: str | Path) -> FloatArray:
    """Read a ``t,x,y,theta`` CSV (s, m, m, rad) into an (N, 4) array.

    Blank lines are skipped. Any other problem raises TrajectoryFormatError("FILE:LINE: ...").
    """
    path = Path(path)
    rows: list[list[float]] = []
    last_t = -math.inf
    for lineno, cells in _csv_records(path, TRAJECTORY_HEADER, "trajectory CSV", TRAJECTORY_SAMPLES.value()):
        values = _numbers(path, lineno, TRAJECTORY_HEADER, cells)
        _check_sample(path, lineno, values, cells, last_t)
        last_t = values[0]
        rows.append(values)
    if not rows:
        raise TrajectoryFormatError(f"{path}: header only, no samples")
    if rows[-1][0] - rows[0][0] <= 0.0:
        raise TrajectoryFormatError(f"{path}: the trajectory lasts 0 s ({len(rows)} sample(s), all at "
                                    f"t = {rows[0][0]:g} s); metrics need at least two samples at different times")
    return np.asarray(rows, dtype=np.float64)


def cell_text(cell: str) -> str:
    """A CSV cell as quoted in a message, cut short (a cell may be megabytes long)."""
    return cell if len(cell) <= 30 else cell[:27] + "..."


PEOPLE_HEADER: tuple[str, ...] = ("t", "name", "role", "x", "y", "theta", "vx", "vy", "group")


def read_people_csv(path: str | Path) -> PeopleTracks:
    """Read a ``people.csv`` (the simulator writes it beside trajectory.csv: header
    ``t,name,role,x,y,theta,vx,vy,group``; s, -, -, m, m, rad, m/s, m/s, a group label or empty)
    into tracks.

    Any problem raises TrajectoryFormatError("FILE:LINE: ...")."""
    path = Path(path)
    rows: list[tuple[float, str, float, float, float, float, float, str, str]] = []
    last_t = -math.inf
    for lineno, cells in _csv_records(path, PEOPLE_HEADER, "people CSV", TRAJECTORY_SAMPLES.value() * 50):
        t_cell, name, role, *numbers, group = cells
        values = _numbers(path, lineno, ("t", "x", "y", "theta", "vx", "vy"), [t_cell, *numbers])
        if not name:
            raise TrajectoryFormatError(f"{path}:{lineno}: column 'name' is empty; each row is one person")
        _check_sample(path, lineno, values, [t_cell, *numbers], last_t)
        last_t = values[0]
        rows.append((values[0], cell_text(name), values[1], values[2], values[3], values[4], values[5], group,
                     cell_text(role)))
    return tracks_from_rows(rows)
