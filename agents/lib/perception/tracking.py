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

A track whose detection falls outside its gate (a sudden turn or start) is *re-acquired* when the
detector names it: it jumps to the detection and keeps its history, so its velocity comes from the
fit (never reset to zero, which made 12 % of ETH tracks restart in 3.2 s).  After a gap longer than
``MAX_GAP_S`` (the simulator skipped an idle stretch) the prediction says nothing useful: the
tracks restart from the detections, named by the detector.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

GATE_CHI2 = 9.21            # 2 degrees of freedom, 99 %
NAME_MISMATCH_CHI2 = 6.0    # association cost of a detection named after someone else (module doc)
MAX_GAP_S = 2.0
LOST_S = 3.0                # a track not updated for this long reports no velocity
STILL_MPS = 0.1             # an estimated speed below this is sensor noise on a still person
MIN_SIGMA_M = 0.01          # the measurement noise the tracker assumes at least (a perfect sensor is never perfect)
SMOOTHING_S = 1.2           # at most this many seconds of detections in the velocity's line fit
VELOCITY_SIGMA_MPS = 0.04   # the velocity noise the fit aims at: as few detections as reach it (module doc)


def observer_tracker(noise_xy: float) -> Tracker:
    """The tracker as the human observer deploys it for a detector of ``noise_xy`` m position noise.

    One definition: the observer and ``chronav predict evaluate`` build it here, so the benchmark
    measures what runs."""
    return Tracker(measurement_sigma=max(noise_xy, MIN_SIGMA_M))


@dataclass(frozen=True)
class Detection:
    name: str           # who the detector says it is (used to name a new track)
    x: float
    y: float
    theta: float


@dataclass
class Track:
    name: str
    state: NDArray[np.float64]        # x, y, vx, vy
    cov: NDArray[np.float64]          # 4 x 4
    theta: float
    updated_s: float
    history: list[tuple[float, float, float]] = field(default_factory=list)   # (t, x, y) of its detections

    @property
    def xy(self) -> tuple[float, float]:
        return float(self.state[0]), float(self.state[1])

    @property
    def velocity(self) -> tuple[float, float]:
        return float(self.state[2]), float(self.state[3])


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
    tracks: dict[str, Track] = field(default_factory=dict)
    last_s: float | None = None

    def update(self, t_s: float, detections: Sequence[Detection]) -> dict[str, Track]:
        """Predict every track to ``t_s``, associate the detections, correct; re-acquire or start
        tracks for the rest."""
        gap = math.inf if self.last_s is None else t_s - self.last_s
        self.last_s = t_s
        if gap > MAX_GAP_S or gap < 0:
            self.tracks = {d.name: self._new(d, t_s) for d in detections}
            return self.tracks
        names = sorted(self.tracks)
        for name in names:
            self._predict(self.tracks[name], gap)
        unmatched = list(range(len(detections)))
        matched: set[str] = set()
        if names and detections:
            # Squared Mahalanobis distance of every detection to every predicted track, at once.
            predicted = np.array([self.tracks[n].state[:2] for n in names])                   # (T, 2)
            inv = np.linalg.inv(np.array([self.tracks[n].cov[:2, :2] for n in names])
                                + np.eye(2) * self.measurement_sigma ** 2)                      # (T, 2, 2)
            measured = np.array([[d.x, d.y] for d in detections])                              # (D, 2)
            innovation = measured[None, :, :] - predicted[:, None, :]                          # (T, D, 2)
            d2 = np.einsum("tdi,tij,tdj->td", innovation, inv, innovation)
            other = np.array([[d.name != n for d in detections] for n in names], dtype=np.float64)
            cost = np.where(d2 <= GATE_CHI2, d2 + NAME_MISMATCH_CHI2 * other, 1e6)
            rows, cols = linear_sum_assignment(cost)
            for r, c in zip(rows, cols, strict=True):
                if cost[r, c] >= 1e6:
                    continue
                self._correct(self.tracks[names[r]], detections[c], t_s)
                matched.add(names[r])
                unmatched.remove(c)
        for c in unmatched:
            det = detections[c]
            old = self.tracks.get(det.name)
            if old is not None and det.name not in matched and t_s - old.updated_s <= LOST_S:
                self._reacquire(old, det, t_s)
            else:
                # A person the detector names but no track explains: (re)start that name's track.
                self.tracks[det.name] = self._new(det, t_s)
        return self.tracks

    def _new(self, det: Detection, t_s: float) -> Track:
        cov = np.diag([self.measurement_sigma ** 2, self.measurement_sigma ** 2,
                       self.initial_speed_sigma ** 2, self.initial_speed_sigma ** 2])
        return Track(det.name, np.array([det.x, det.y, 0.0, 0.0]), cov, det.theta, t_s, [(t_s, det.x, det.y)])

    def _predict(self, track: Track, dt: float) -> None:
        f = np.eye(4)
        f[0, 2] = f[1, 3] = dt
        q = self.accel_sigma ** 2 * np.array([[dt**4 / 4, 0, dt**3 / 2, 0], [0, dt**4 / 4, 0, dt**3 / 2],
                                              [dt**3 / 2, 0, dt**2, 0], [0, dt**3 / 2, 0, dt**2]])
        track.state = f @ track.state
        track.cov = f @ track.cov @ f.T + q

    def _correct(self, track: Track, det: Detection, t_s: float) -> None:
        h = np.zeros((2, 4))
        h[0, 0] = h[1, 1] = 1.0
        s = h @ track.cov @ h.T + np.eye(2) * self.measurement_sigma ** 2
        gain = track.cov @ h.T @ np.linalg.inv(s)
        track.state = track.state + gain @ (np.array([det.x, det.y]) - h @ track.state)
        track.cov = (np.eye(4) - gain @ h) @ track.cov
        self._smooth(track, det, t_s)

    def _reacquire(self, track: Track, det: Detection, t_s: float) -> None:
        """Jump to the detection; the velocity comes from the fit over the kept detections (or stays
        what it was), never from zero; its uncertainty grows so that the gate opens."""
        track.state = np.array([det.x, det.y, track.state[2], track.state[3]])
        track.cov = np.diag([self.measurement_sigma ** 2, self.measurement_sigma ** 2,
                             self.initial_speed_sigma ** 2 / 4, self.initial_speed_sigma ** 2 / 4])
        self._smooth(track, det, t_s)

    def _smooth(self, track: Track, det: Detection, t_s: float) -> None:
        """Keep the detection (at most ``smoothing_s`` of them); position and velocity from the line
        fitted to the fewest latest detections that reach ``velocity_sigma`` (module doc)."""
        history = track.history
        history.append((t_s, det.x, det.y))
        while history and history[0][0] < t_s - self.smoothing_s - 1e-6:
            history.pop(0)
        fit = line_fit(latest_enough(history, self.measurement_sigma, self.velocity_sigma), t_s)
        if fit is not None:
            track.state = np.array(fit)
        turn = (det.theta - track.theta + math.pi) % (2 * math.pi) - math.pi
        track.theta = (track.theta + self.heading_smoothing * turn + math.pi) % (2 * math.pi) - math.pi
        track.updated_s = t_s

    def velocity(self, name: str, t_s: float) -> tuple[float, float]:
        track = self.tracks[name]
        if t_s - track.updated_s > LOST_S:
            return (0.0, 0.0)
        return track.velocity

    def estimate(self, name: str, t_s: float) -> tuple[float, float, float, float, float]:
        """What the observer publishes of a track: x, y, heading, vx, vy (a speed below
        ``STILL_MPS`` is reported as standing still)."""
        track = self.tracks[name]
        vx, vy = self.velocity(name, t_s)
        if math.hypot(vx, vy) < STILL_MPS:
            vx = vy = 0.0
        return (*track.xy, track.theta, vx, vy)


def latest_enough(samples: Sequence[tuple[float, float, float]], sigma: float,
                  velocity_sigma: float) -> Sequence[tuple[float, float, float]]:
    """The fewest latest (t, x, y) samples, at least two, whose fitted slope has a standard deviation
    of at most ``velocity_sigma`` for position noise ``sigma``; all of them if none do.  Fewer
    samples follow turns and stops sooner; more average the noise away."""
    for k in range(2, len(samples) + 1):
        times = [s[0] for s in samples[-k:]]
        mean = sum(times) / k
        spread = sum((t - mean) ** 2 for t in times)
        if spread > 0 and sigma * sigma <= velocity_sigma * velocity_sigma * spread:
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
