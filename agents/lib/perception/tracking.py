"""Multi-person tracking: detections associated to tracks by Mahalanobis distance (Hungarian
assignment) under a constant-velocity Kalman filter, identities kept by the tracks; each track's
position and velocity from a straight line fitted to its latest detections.

Why a tracker and not raw detections: the social map stretches a walking person's space along
their velocity and predicts where they will be, so the velocity must be estimated from noisy
positions; and identities must survive two people passing close to each other, which is exactly
when nearest-name matching would swap them.  A detector (re-identification camera) names a person
when it first sees them; from then on the track keeps its name and follows the detections its
motion model predicts (Bar-Shalom and Li, "Multitarget-Multisensor Tracking", 1995: CV model,
gating at the chi-square 99 % bound, global nearest neighbour assignment).  Inside the gate a
detection named after the track costs ``NAME_MISMATCH_CHI2`` less than one named after someone
else: the detector's name settles near ties (two people side by side), a clear motion still
overrides a wrong name.

Why the velocity is not the Kalman filter's: with the observer's 2 cm noise and people's
1.5 m/s^2 accelerations, a Kalman filter at 2.5 Hz has gains alpha ~ 0.98, beta ~ 1.5, and its
velocity is *noisier* than differencing the last two detections (measured with ``chronav predict
evaluate``: 1.47x the constant-velocity error on the two UCY files, 1.13x with the fit).  The
fit takes the fewest latest detections whose slope has a noise of at most ``velocity_sigma``
(0.04 m/s) for the detector's noise ``measurement_sigma``: the slope's variance is
``sigma^2 / sum (t - mean t)^2``, so the window adapts to the detector's noise *and rate* (2 cm:
the last 3 detections at 2.5 Hz, 0.8 s; 7 at the observer's 10 Hz, 0.6 s; 1 cm: the last 2 at
2.5 Hz, plain differencing), never more than ``smoothing_s``.  The Kalman filter keeps the
covariance that sizes the gate; its state is re-seeded from the fit.

Where the walker model applies (walker_model.py: a walker seen over the last 3.2 s), the velocity
the tracker reports (``estimate``) is the fit's corrected by that tiny learned network: the
constant velocity that best predicts the next 4.8 s, learned on real pedestrians with the
observer's noise; elsewhere (young tracks, standing people) the fit's velocity stands.  The
detections of the model's window are kept with the track (``MODEL_WINDOW_S``).

A track whose detection falls outside its gate (a sudden turn or start) is *re-acquired* when the
detector names it: it jumps to the detection and keeps its history, so its velocity comes from the
fit (never reset to zero, which made 12 % of ETH tracks restart in 3.2 s).  After a gap longer than
``MAX_GAP_S`` (the simulator skipped an idle stretch) the prediction says nothing useful: the
tracks restart from the detections, named by the detector.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

from agents.lib.perception import walker_model
from agents.lib.perception.walker_model import WalkerModel
from scenes.angles import wrap_angle

GATE_CHI2 = 9.21            # 2 degrees of freedom, 99 %
NAME_MISMATCH_CHI2 = 6.0    # association cost of a detection named after someone else (module doc)
MAX_GAP_S = 2.0
LOST_S = 3.0                # a track not updated for this long reports no velocity
ASSOCIATE_S = 1.0           # a track not updated for this long is matched by its own name only
STILL_MPS = 0.1             # an estimated speed below this is sensor noise on a still person
MIN_SIGMA_M = 0.01          # the measurement noise the tracker assumes at least (a perfect sensor is never perfect)
SMOOTHING_S = 1.2           # at most this many seconds of detections in the velocity's line fit
VELOCITY_SIGMA_MPS = 0.04   # the velocity noise the fit aims at: as few detections as reach it (module doc)
#: the human observer's default detector: 2 cm of position noise per axis (its ``noise_xy`` option),
#: what ``chronav predict evaluate`` assumes unless told otherwise (one value, so the two agree)
OBSERVER_NOISE_M = 0.02
MODEL_WINDOW_S = (walker_model.LAGS - 0.5) * walker_model.GRID_S   # the detections the walker model reads


def observer_tracker(noise_xy: float, model: WalkerModel | None = None, learned: bool = True) -> Tracker:
    """The tracker as the human observer deploys it for a detector of ``noise_xy`` m position noise,
    with the shipped walker model (walker_model.py) unless ``model`` gives another (``chronav predict
    evaluate --model``: a model trained on other files, for cross-file figures) when it was trained
    for this detector's noise (``WalkerModel.applies_to``); ``learned=False``: the line fit's
    velocity only (what the training script reads the model's inputs from).

    One definition: the observer and ``chronav predict evaluate`` build it here, so the benchmark
    measures what runs."""
    sigma = max(noise_xy, MIN_SIGMA_M)
    model = (model or walker_model.shipped()) if learned else None
    return Tracker(measurement_sigma=sigma, model=model if model is not None and model.applies_to(sigma) else None,
                   still_mps=still_threshold(noise_xy))


def still_threshold(noise_xy: float) -> float:
    """The speed below which the tracker reports a person of a ``noise_xy`` m detector as standing:
    ``STILL_MPS`` (about 2.5 standard deviations of the fit's velocity noise, which is about
    ``VELOCITY_SIGMA_MPS`` for any detector of ``MIN_SIGMA_M`` or worse: a worse one averages more
    detections), scaled down for a better detector, whose velocity noise is proportionally smaller,
    to zero for a perfect one.  Why: UCY annotates people drifting at 0.02-0.1 m/s (a fifth of the
    crowds_zara03 windows); a perfect detector reporting them as standing made the prediction 1.8 %
    worse than constant velocity there (docs/prediction.md)."""
    return STILL_MPS * min(1.0, max(noise_xy, 0.0) / MIN_SIGMA_M)


@dataclass(frozen=True)
class Detection:
    name: str           # who the detector says it is (used to name a new track)
    x: float
    y: float
    theta: float


@dataclass(slots=True)
class Track:
    """One person's track: position and velocity (from the fit), the Kalman covariance that sizes
    its gate, its heading and its latest detections.  The constant-velocity model's two axes are
    independent with the same noises, so one (position, velocity) covariance ``p00, p01, p11``
    serves both: plain float arithmetic, no 4 x 4 matrices, per track and cycle."""

    name: str
    x: float
    y: float
    vx: float
    vy: float
    p00: float
    p01: float
    p11: float
    theta: float
    updated_s: float
    history: list[tuple[float, float, float]] = field(default_factory=list)   # (t, x, y) of its detections

    @property
    def xy(self) -> tuple[float, float]:
        return self.x, self.y

    @property
    def velocity(self) -> tuple[float, float]:
        return self.vx, self.vy


@dataclass
class Tracker:
    """Tracks gated and associated by a constant-velocity Kalman filter (``accel_sigma`` m/s^2
    white-noise acceleration, ``measurement_sigma`` m position noise); position and velocity from
    the line fit of the module doc."""

    measurement_sigma: float = 0.05
    accel_sigma: float = 1.5
    initial_speed_sigma: float = 1.0
    heading_smoothing: float = 0.5
    smoothing_s: float = SMOOTHING_S
    velocity_sigma: float = VELOCITY_SIGMA_MPS
    still_mps: float = STILL_MPS              # slower is reported as standing (``still_threshold``)
    model: WalkerModel | None = None          # the learned velocity correction (walker_model.py); None: the fit's
    tracks: dict[str, Track] = field(default_factory=dict)
    last_s: float | None = None
    _corrected: dict[str, tuple[float, float]] | None = field(default=None, init=False, repr=False)  # at ``last_s``

    def update(self, t_s: float, detections: Sequence[Detection]) -> dict[str, Track]:
        """Predict every track to ``t_s``, associate the detections, correct; re-acquire or start
        tracks for the rest."""
        gap = math.inf if self.last_s is None else t_s - self.last_s
        self.last_s = t_s
        self._corrected = None
        if gap > MAX_GAP_S or gap < 0:
            self.tracks = {d.name: self._new(d, t_s) for d in detections}
            return self.tracks
        for track in self.tracks.values():
            self._predict(track, gap)
        # A track missed for ASSOCIATE_S takes part in the assignment no more: only a detection named
        # after it re-acquires it (below).  Else a person entering where another left (a replayed
        # crowd) was taken for them, and the gone person's track walked off with the newcomer.
        names = sorted(n for n, track in self.tracks.items() if t_s - track.updated_s <= ASSOCIATE_S)
        tracks = [self.tracks[n] for n in names]
        unmatched = list(range(len(detections)))
        matched: set[str] = set()
        if tracks and detections:
            # Squared Mahalanobis distance of every detection to every predicted track, at once
            # (isotropic: both axes share the covariance).
            r = self.measurement_sigma ** 2
            predicted = np.array([(t.x, t.y) for t in tracks])                                 # (T, 2)
            spread = np.array([t.p00 + r for t in tracks])                                      # (T,)
            measured = np.array([(d.x, d.y) for d in detections])                              # (D, 2)
            d2 = ((measured[None, :, :] - predicted[:, None, :]) ** 2).sum(axis=2) / spread[:, None]
            other = np.array([[d.name != n for d in detections] for n in names], dtype=np.float64)
            cost = np.where(d2 <= GATE_CHI2, d2 + NAME_MISMATCH_CHI2 * other, 1e6)
            rows, cols = linear_sum_assignment(cost)
            for row, col in zip(rows.tolist(), cols.tolist(), strict=True):
                if cost[row, col] >= 1e6:
                    continue
                self._correct(tracks[row], detections[col], t_s)
                matched.add(names[row])
                unmatched.remove(col)
        for col in unmatched:
            det = detections[col]
            old = self.tracks.get(det.name)
            if old is not None and det.name not in matched and t_s - old.updated_s <= LOST_S:
                self._reacquire(old, det, t_s)
            else:
                # A person the detector names but no track explains: (re)start that name's track.
                self.tracks[det.name] = self._new(det, t_s)
        return self.tracks

    def _new(self, det: Detection, t_s: float) -> Track:
        return Track(det.name, det.x, det.y, 0.0, 0.0, self.measurement_sigma ** 2, 0.0,
                     self.initial_speed_sigma ** 2, det.theta, t_s, [(t_s, det.x, det.y)])

    def _predict(self, track: Track, dt: float) -> None:
        """x += v dt; P = F P F' + Q with Q the white-noise acceleration's (Bar-Shalom and Li)."""
        q = self.accel_sigma ** 2
        track.x += track.vx * dt
        track.y += track.vy * dt
        track.p00 += dt * (2.0 * track.p01 + dt * track.p11) + q * dt ** 4 / 4.0
        track.p01 += dt * track.p11 + q * dt ** 3 / 2.0
        track.p11 += q * dt ** 2

    def _correct(self, track: Track, det: Detection, t_s: float) -> None:
        s = track.p00 + self.measurement_sigma ** 2
        k0, k1 = track.p00 / s, track.p01 / s
        ix, iy = det.x - track.x, det.y - track.y
        track.x += k0 * ix
        track.y += k0 * iy
        track.vx += k1 * ix
        track.vy += k1 * iy
        track.p11 -= k1 * track.p01
        track.p00 *= 1.0 - k0
        track.p01 *= 1.0 - k0
        self._smooth(track, det, t_s)

    def _reacquire(self, track: Track, det: Detection, t_s: float) -> None:
        """Jump to the detection; the velocity comes from the fit over the kept detections (or stays
        what it was), never from zero; its uncertainty grows so that the gate opens."""
        track.x, track.y = det.x, det.y
        track.p00, track.p01, track.p11 = self.measurement_sigma ** 2, 0.0, self.initial_speed_sigma ** 2 / 4
        self._smooth(track, det, t_s)

    def _smooth(self, track: Track, det: Detection, t_s: float) -> None:
        """Keep the detection (at most ``smoothing_s`` of them); position and velocity from the line
        fitted to the fewest latest detections that reach ``velocity_sigma`` (module doc)."""
        history = track.history
        history.append((t_s, det.x, det.y))
        keep_s = max(self.smoothing_s, MODEL_WINDOW_S)
        while history and history[0][0] < t_s - keep_s - 1e-6:
            history.pop(0)
        recent = history[bisect.bisect_left(history, t_s - self.smoothing_s - 1e-6, key=lambda h: h[0]):]
        fit = line_fit(latest_enough(recent, self.measurement_sigma, self.velocity_sigma), t_s)
        if fit is not None:
            track.x, track.y, track.vx, track.vy = fit
        turn = wrap_angle(det.theta - track.theta)
        track.theta = wrap_angle(track.theta + self.heading_smoothing * turn)
        track.updated_s = t_s

    def velocity(self, name: str, t_s: float) -> tuple[float, float]:
        track = self.tracks[name]
        if t_s - track.updated_s > LOST_S:
            return (0.0, 0.0)
        return track.velocity

    def model_inputs(self, names: Sequence[str], t_s: float) -> dict[str, tuple[NDArray[np.float64], float, float]]:
        """The walker model's features of the named tracks it applies to, with the fit's velocity
        they are relative to: not lost, walking (at least the model's ``min_speed_mps``, else
        ``STILL_MPS``), seen over the model's whole window; the others keep the fit's velocity (the
        constant-velocity fallback).  One definition for the live path and the training script."""
        least = max(self.model.min_speed_mps if self.model is not None else STILL_MPS, 1e-9)
        tracks = [self.tracks[n] for n in names]
        chosen = [tr for tr in tracks if t_s - tr.updated_s <= LOST_S and math.hypot(tr.vx, tr.vy) >= least]
        if not chosen:
            return {}
        points, full = walker_model.windows([tr.history for tr in chosen], t_s)
        if not full.any():
            return {}
        velocity = np.array([(tr.vx, tr.vy) for tr in chosen])
        found = walker_model.features(points[full], velocity[full])
        kept = [tr for tr, ok in zip(chosen, full.tolist(), strict=True) if ok]
        return {tr.name: (f, tr.vx, tr.vy) for tr, f in zip(kept, found, strict=True)}

    def _learned(self, t_s: float) -> dict[str, tuple[float, float]]:
        """Every applicable track's velocity corrected by the model, in one numpy pass per cycle
        (the observer asks for everyone's estimate at the same time)."""
        if self._corrected is not None:
            return self._corrected
        inputs = self.model_inputs(list(self.tracks), t_s)
        self._corrected = {}
        if inputs and self.model is not None:
            corrections = self.model.corrections(np.array([f for f, _, _ in inputs.values()]))
            for (name, (_, vx, vy)), (along, across) in zip(inputs.items(), corrections.tolist(), strict=True):
                speed = math.hypot(vx, vy)
                c, s = vx / speed, vy / speed
                self._corrected[name] = (vx + along * c - across * s, vy + along * s + across * c)
        return self._corrected

    def estimate(self, name: str, t_s: float) -> tuple[float, float, float, float, float]:
        """What the observer publishes of a track: x, y, heading, vx, vy; the velocity is the walker
        model's where it applies (``model_inputs``), else the fit's; a speed below ``still_mps`` is
        reported as standing still."""
        track = self.tracks[name]
        vx, vy = self.velocity(name, t_s)
        if self.model is not None and self.last_s == t_s:
            vx, vy = self._learned(t_s).get(name, (vx, vy))
        if math.hypot(vx, vy) < self.still_mps:
            vx = vy = 0.0
        return track.x, track.y, track.theta, vx, vy


def latest_enough(samples: Sequence[tuple[float, float, float]], sigma: float,
                  velocity_sigma: float) -> Sequence[tuple[float, float, float]]:
    """The fewest latest (t, x, y) samples, at least two, whose fitted slope has a standard deviation
    of at most ``velocity_sigma`` for position noise ``sigma``; all of them if none do.  Fewer
    samples follow turns and stops sooner; more average the noise away."""
    need = (sigma / velocity_sigma) ** 2 if velocity_sigma > 0 else math.inf
    total = total_sq = 0.0
    t0 = samples[-1][0] if samples else 0.0
    for k in range(1, len(samples) + 1):
        t = samples[-k][0] - t0               # relative times: no cancellation in the spread
        total += t
        total_sq += t * t
        if k >= 2 and total_sq - total * total / k >= need:
            return samples[-k:]
    return samples


def line_fit(samples: Sequence[tuple[float, float, float]], t_s: float) -> tuple[float, float, float, float] | None:
    """Least-squares straight line through (t, x, y) samples: (x, y) at ``t_s`` and (vx, vy); None
    with fewer than two distinct times.  Plain Python: a handful of samples per track and
    detection, where numpy's per-call overhead would dominate."""
    n = len(samples)
    if n < 2:
        return None
    tm = sum(s[0] for s in samples) / n
    xm = sum(s[1] for s in samples) / n
    ym = sum(s[2] for s in samples) / n
    stt = sxt = syt = 0.0
    for t, x, y in samples:
        dt = t - tm
        stt += dt * dt
        sxt += dt * (x - xm)
        syt += dt * (y - ym)
    if stt <= 1e-12:
        return None
    vx, vy = sxt / stt, syt / stt
    return xm + vx * (t_s - tm), ym + vy * (t_s - tm), vx, vy
