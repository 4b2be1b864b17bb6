"""Multi-person tracking: a constant-velocity Kalman filter per person, detections associated by
Mahalanobis distance (Hungarian assignment), identities kept by the tracks.

Why a tracker and not raw detections: the social map stretches a walking person's space along
their velocity and predicts where they will be, so the velocity must be estimated from noisy
positions; and identities must survive two people passing close to each other, which is exactly
when nearest-name matching would swap them.  A detector (re-identification camera) names a person
when it first sees them; from then on the track keeps its name and follows the detections its
motion model predicts (Bar-Shalom and Li, "Multitarget-Multisensor Tracking", 1995: CV model,
gating at the chi-square 99 % bound, global nearest neighbour assignment).

After a gap longer than ``MAX_GAP_S`` (the simulator skipped an idle stretch) the prediction says
nothing useful: the tracks restart from the detections, named by the detector.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

GATE_CHI2 = 9.21        # 2 degrees of freedom, 99 %
MAX_GAP_S = 2.0
LOST_S = 3.0            # a track not updated for this long reports no velocity


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

    @property
    def xy(self) -> tuple[float, float]:
        return float(self.state[0]), float(self.state[1])

    @property
    def velocity(self) -> tuple[float, float]:
        return float(self.state[2]), float(self.state[3])


@dataclass
class Tracker:
    """Constant-velocity Kalman tracks (``accel_sigma`` m/s^2 white-noise acceleration,
    ``measurement_sigma`` m position noise)."""

    measurement_sigma: float = 0.05
    accel_sigma: float = 1.5
    initial_speed_sigma: float = 1.0
    heading_smoothing: float = 0.5
    tracks: dict[str, Track] = field(default_factory=dict)
    last_s: float | None = None

    def update(self, t_s: float, detections: Sequence[Detection]) -> dict[str, Track]:
        """Predict every track to ``t_s``, associate the detections, correct; new tracks for the rest."""
        gap = math.inf if self.last_s is None else t_s - self.last_s
        self.last_s = t_s
        if gap > MAX_GAP_S or gap < 0:
            self.tracks = {d.name: self._new(d, t_s) for d in detections}
            return self.tracks
        names = sorted(self.tracks)
        for name in names:
            self._predict(self.tracks[name], gap)
        unmatched = list(range(len(detections)))
        if names and detections:
            # Squared Mahalanobis distance of every detection to every predicted track, at once.
            predicted = np.array([self.tracks[n].state[:2] for n in names])                   # (T, 2)
            inv = np.linalg.inv(np.array([self.tracks[n].cov[:2, :2] for n in names])
                                + np.eye(2) * self.measurement_sigma ** 2)                      # (T, 2, 2)
            measured = np.array([[d.x, d.y] for d in detections])                              # (D, 2)
            innovation = measured[None, :, :] - predicted[:, None, :]                          # (T, D, 2)
            d2 = np.einsum("tdi,tij,tdj->td", innovation, inv, innovation)
            cost = np.where(d2 <= GATE_CHI2, d2, 1e6)
            rows, cols = linear_sum_assignment(cost)
            for r, c in zip(rows, cols, strict=True):
                if cost[r, c] >= 1e6:
                    continue
                self._correct(self.tracks[names[r]], detections[c], t_s)
                unmatched.remove(c)
        for c in unmatched:
            det = detections[c]
            # A person the detector names but no track explains: (re)start that name's track.
            self.tracks[det.name] = self._new(det, t_s)
        return self.tracks

    def _new(self, det: Detection, t_s: float) -> Track:
        cov = np.diag([self.measurement_sigma ** 2, self.measurement_sigma ** 2,
                       self.initial_speed_sigma ** 2, self.initial_speed_sigma ** 2])
        return Track(det.name, np.array([det.x, det.y, 0.0, 0.0]), cov, det.theta, t_s)

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
        turn = (det.theta - track.theta + math.pi) % (2 * math.pi) - math.pi
        track.theta = (track.theta + self.heading_smoothing * turn + math.pi) % (2 * math.pi) - math.pi
        track.updated_s = t_s

    def velocity(self, name: str, t_s: float) -> tuple[float, float]:
        track = self.tracks[name]
        if t_s - track.updated_s > LOST_S:
            return (0.0, 0.0)
        return track.velocity
