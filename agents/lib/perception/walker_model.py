"""A learned correction of a walker's velocity: a tiny neural network (one hidden layer of
``hidden`` tanh units) that reads the track's last 3.2 s in the walker's own frame and says which
constant velocity best predicts the next 4.8 s.

Why: the line fit of the tracker (tracking.py) estimates the *current* velocity; what the social
map needs is the velocity that best predicts where the person will be (people slow down, speed up,
curve, and the fit's heading is noisy).  A linear map from the observed window cannot do better
than the fit (docs/prediction.md: measured 1.13x constant velocity on true positions, like the
fit); a small nonlinear one, trained on real pedestrians with the observer's noise, gains a few
per cent on files it has never seen.  It outputs one velocity, not a curved path, so what the
observer publishes (x, y, vx, vy) and the social map's ``motion.predict_many`` stay as they are:
the correction is the velocity the tracker reports (``Tracker.estimate``), on the live path and in
``chronav predict evaluate`` alike.

**Input** (``windows``): the track's detections on a 0.4 s grid reaching ``LAGS`` steps back from
now, each grid point the mean of the detections nearest to it (at 2.5 Hz one detection, at
the observer's 10 Hz four: the model does not depend on the detector's rate), rotated so that the
tracker's velocity points along +x; the features are the ``LAGS - 1`` steps of that window as
velocities (m/s) and the tracker's speed.  **Output**: a correction (along, across) in that frame,
added to the tracker's velocity, bounded by ``max_correction_mps`` (outside the training data a
network may say anything; the bound keeps a surprise small).  The model applies to walkers only
(tracker speed at least ``min_speed_mps``) whose track covers the whole window; others keep the
fit's velocity (constant-velocity fallback); and only to a detector of about the noise it was
trained for (``applies_to``).

**Parameters** come from ``tools/train_prediction.py`` (seeded and deterministic: the command, the
files with their sha256 and the seed are in the file's ``provenance``) and ship as
``walker_model.json`` next to this module.  A missing, malformed or incompatible file is a
``WalkerModelError`` naming the file and the key.
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

FORMAT = "chronav-walker-model"
VERSION = 1
LAGS = 8                     # grid points of the window: now and 7 x 0.4 s back (3.2 s observed, the benchmark's)
GRID_S = 0.4
FEATURES = 2 * (LAGS - 1) + 1   # the window's steps (along, across) and the speed
DEFAULT_PATH = Path(__file__).with_name("walker_model.json")


class WalkerModelError(ValueError):
    """The learned model's parameter file cannot be used: the message names the file and the key."""


@dataclass(frozen=True)
class WalkerModel:
    """The network's parameters (module doc) and where they come from."""

    mean: NDArray[np.float64]        # (F,) feature standardisation
    scale: NDArray[np.float64]       # (F,)
    w1: NDArray[np.float64]          # (F, H)
    b1: NDArray[np.float64]          # (H,)
    w2: NDArray[np.float64]          # (H, 2)
    b2: NDArray[np.float64]          # (2,)
    min_speed_mps: float
    max_correction_mps: float
    noise_m: float                   # the detection noise it was trained for (``applies_to``)
    provenance: dict[str, Any]

    @property
    def features(self) -> int:
        return len(self.mean)

    def applies_to(self, noise_xy: float) -> bool:
        """Whether a detector of ``noise_xy`` m is the one the model learned to correct (within a
        factor of 1.5 of ``noise_m``).  Its corrections are learned from what that noise does to
        the fit; with a much better detector the fit alone is better (on simulated center_day
        people without noise the corrections cost 3 % of ADE: docs/prediction.md), so another
        detector keeps the fit's velocity until a model is trained for it (``--noise``)."""
        return self.noise_m / 1.5 <= noise_xy <= self.noise_m * 1.5

    def corrections(self, features: NDArray[np.float64]) -> NDArray[np.float64]:
        """(N, F) features -> (N, 2) velocity corrections (along, across), bounded (module doc)."""
        hidden = np.tanh(((features - self.mean) / self.scale) @ self.w1 + self.b1)
        out = hidden @ self.w2 + self.b2
        norm = np.hypot(out[:, 0], out[:, 1])
        too_big = norm > self.max_correction_mps
        out[too_big] *= (self.max_correction_mps / norm[too_big])[:, None]
        return out

    def to_json(self) -> dict[str, Any]:
        return {"format": FORMAT, "version": VERSION, "lags": LAGS, "grid_s": GRID_S,
                "min_speed_mps": self.min_speed_mps, "max_correction_mps": self.max_correction_mps,
                "noise_m": self.noise_m,
                "provenance": self.provenance,
                "mean": _rounded(self.mean), "scale": _rounded(self.scale), "w1": _rounded(self.w1),
                "b1": _rounded(self.b1), "w2": _rounded(self.w2), "b2": _rounded(self.b2)}


def _rounded(a: NDArray[np.float64]) -> list[Any]:
    """Ten significant digits: enough for the network, short to read and diff.  (Training is
    deterministic on one machine; another BLAS may differ in the last digits.)"""
    return np.vectorize(lambda v: float(f"{v:.10g}"), otypes=[float])(a).tolist()


def _array(path: Path, raw: dict[str, Any], key: str, shape: tuple[int, ...]) -> NDArray[np.float64]:
    try:
        a = np.asarray(raw[key], dtype=np.float64)
    except KeyError:
        raise WalkerModelError(f"{path}: key {key!r} is missing") from None
    except (TypeError, ValueError):
        raise WalkerModelError(f"{path}: key {key!r} must be numbers") from None
    if a.shape != shape:
        raise WalkerModelError(f"{path}: key {key!r} has shape {list(a.shape)}, expected {list(shape)}")
    if not np.all(np.isfinite(a)):
        raise WalkerModelError(f"{path}: key {key!r} holds a value that is not a finite number")
    return a


def from_json(raw: Any, path: Path) -> WalkerModel:
    """Validate a parsed parameter file (module doc): errors name the file and the key."""
    if not isinstance(raw, dict):
        raise WalkerModelError(f"{path}: expected a JSON object")
    if raw.get("format") != FORMAT:
        raise WalkerModelError(f"{path}: key 'format' must be {FORMAT!r}, found {raw.get('format')!r}")
    if raw.get("version") != VERSION:
        raise WalkerModelError(f"{path}: key 'version' is {raw.get('version')!r}; this chronav reads version "
                               f"{VERSION} (retrain with tools/train_prediction.py)")
    if raw.get("lags") != LAGS or raw.get("grid_s") != GRID_S:
        raise WalkerModelError(f"{path}: keys 'lags'/'grid_s' must be {LAGS}/{GRID_S} (the window this chronav builds)")
    features = FEATURES
    try:
        hidden = len(raw["b1"])
    except (KeyError, TypeError):
        raise WalkerModelError(f"{path}: key 'b1' is missing or not a list") from None
    provenance = raw.get("provenance")
    if not isinstance(provenance, dict) or not {"command", "files", "seed"} <= set(provenance):
        raise WalkerModelError(f"{path}: key 'provenance' must name the 'command', 'files' and 'seed' it was trained with")
    limits = []
    for key in ("min_speed_mps", "max_correction_mps", "noise_m"):
        value = raw.get(key)
        if not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
            raise WalkerModelError(f"{path}: key {key!r} must be a number >= 0")
        limits.append(float(value))
    scale = _array(path, raw, "scale", (features,))
    if np.any(scale <= 0):
        raise WalkerModelError(f"{path}: key 'scale' must be positive")
    return WalkerModel(_array(path, raw, "mean", (features,)), scale, _array(path, raw, "w1", (features, hidden)),
                       _array(path, raw, "b1", (hidden,)), _array(path, raw, "w2", (hidden, 2)),
                       _array(path, raw, "b2", (2,)), limits[0], limits[1], limits[2], provenance)


def load(path: Path | str | None = None) -> WalkerModel:
    """The model in ``path`` (default: the one shipped with chronav), validated (module doc)."""
    path = Path(path) if path is not None else DEFAULT_PATH
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise WalkerModelError(f"{path}: no such file (the walker model; train it with "
                               f"chronav predict train)") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise WalkerModelError(f"{path}: cannot be read as JSON ({exc.__class__.__name__}: {exc})") from None
    return from_json(raw, path)


@lru_cache(maxsize=1)
def shipped() -> WalkerModel:
    """The shipped model, loaded once per process."""
    return load(DEFAULT_PATH)


def windows(histories: Sequence[Sequence[tuple[float, float, float]]],
            t_s: float) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Every track's positions on the 0.4 s grid back from ``t_s`` ((N, LAGS, 2), oldest first),
    each grid point the mean of the track's detections nearest to it (within 0.2 s), and whether
    every grid point has one (False: the track is younger than the window, or was not seen for a
    while).  All tracks in one numpy pass: an observer cycle asks for everyone at once."""
    n = len(histories)
    counts = [len(h) for h in histories]
    if n == 0 or sum(counts) == 0:
        return np.zeros((n, LAGS, 2)), np.zeros(n, dtype=bool)
    chain = itertools.chain.from_iterable          # fromiter: a third of np.array's time on nested tuples
    samples = np.fromiter(chain(chain(histories)), np.float64, count=3 * sum(counts)).reshape(-1, 3)   # (M, 3)
    owner = np.repeat(np.arange(n), counts)
    back = np.floor((t_s - samples[:, 0]) / GRID_S + 0.5).astype(np.int64)          # nearest grid point back
    use = (back >= 0) & (back < LAGS)
    cell = owner[use] * LAGS + (LAGS - 1 - back[use])
    number = np.bincount(cell, minlength=n * LAGS).reshape(n, LAGS)
    sums = np.stack([np.bincount(cell, samples[use, 1], n * LAGS), np.bincount(cell, samples[use, 2], n * LAGS)],
                    axis=1).reshape(n, LAGS, 2)
    full: np.ndarray = np.asarray((number > 0).all(axis=1))
    return sums / np.maximum(number, 1)[:, :, None], full


def features(points: NDArray[np.float64], velocity: NDArray[np.float64]) -> NDArray[np.float64]:
    """The model's input ((N, F)) for windows ``points`` ((N, LAGS, 2), ``windows``) and the
    tracker's velocities ((N, 2), non-zero) (module doc): the window's steps as velocities (along,
    across the tracker's velocity; oldest first), then the speed."""
    speed = np.hypot(velocity[:, 0], velocity[:, 1])
    c, s = (velocity[:, 0] / speed)[:, None], (velocity[:, 1] / speed)[:, None]
    steps = np.diff(points, axis=1) / GRID_S                                          # (N, LAGS - 1, 2)
    along = steps[:, :, 0] * c + steps[:, :, 1] * s
    across = -steps[:, :, 0] * s + steps[:, :, 1] * c
    return np.concatenate([np.stack([along, across], axis=2).reshape(len(points), -1), speed[:, None]], axis=1)


def mirrored(features: NDArray[np.float64]) -> NDArray[np.float64]:
    """``features`` of the same walks seen in a mirror (the across components negated): the walker's
    frame makes the model blind to rotation, and a left turn mirrored is a right turn, so the training
    script (tools/train_prediction.py) learns from both and the model cannot prefer a side it happened
    to see more of in one place (cross-file on the two UCY files: 0.944 -> 0.929 of constant velocity
    fed the same detections, docs/prediction.md)."""
    out = features.copy()
    out[:, 1:2 * (LAGS - 1):2] *= -1.0
    return out

