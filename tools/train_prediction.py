"""Train the walker model (agents/lib/perception/walker_model.py) on real pedestrians.

Why a script: the shipped parameters must be reproducible from the data and this file alone.  It
asks the benchmark's question (tools/prediction_eval.py: observe 8 frames = 3.2 s, predict 12 =
4.8 s at 0.4 s, the standard loader's windows) of the observer's tracker *without* the model: each
window start gets a fresh ``observer_tracker(noise, learned=False)`` fed the observed frames of
everyone present, with ``--noise`` m of detection noise drawn per annotation for each of
``--noise-seeds`` (noise augmentation: the same walk seen through different noise; the benchmark's
own seed is 0, so the default training seeds 1 and 2 never see the benchmark's noise), and again
with every walk scaled by ``SCALES`` (speed augmentation); each example is also learned in a mirror
(``walker_model.mirrored``).  For every
window whose track the model applies to (``Tracker.model_inputs``: a walker seen over the whole
3.2 s), the target is the true future in the walker's frame.  The network (one tanh layer) is
fitted by L-BFGS (scipy) from a seeded start, minimising the mean Euclidean distance between the
constant-velocity rollout of the corrected velocity and the true future at the 12 steps (the ADE
itself) plus ``--weight-decay`` x the squared weights; nothing random but the seeded noise and the
seeded start, so the same command gives the same file.

Data rules (scenes/data/pedestrians/SOURCES.md): only the two UCY tuning files; the shipped
model is trained on both.  Cross-file figures (docs/prediction.md): train on one (``--out`` a temp
file), then ``chronav predict evaluate OTHER --noise 0.02 --model THAT``.

Run: ``.venv/bin/python tools/train_prediction.py [FILE ...] [--out agents/lib/perception/walker_model.json]``
"""

from __future__ import annotations

import argparse
import hashlib
import json
import shlex
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

REPO = Path(__file__).resolve().parents[1]
DEFAULT_FILES = sorted((REPO / "scenes" / "data" / "pedestrians").glob("*.txt"))   # shipped (SOURCES.md there)
OBS, PRED, DT = 8, 12, 0.4
#: every walk is also learned scaled by these factors (speed augmentation: the same paths walked slower
#: and faster, seen through the same detector noise): people walk at other speeds at another site, and
#: a model learned on one file's speeds did worse on the other's (docs/prediction.md: cross-file
#: 0.930 -> 0.925 of constant velocity fed the same detections)
SCALES = (1.0, 0.8, 1.25)


def examples(path: Path, noise: float, seed: int, leave_out: tuple[int, int] | None = None,
             scale: float = 1.0) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """(features (N, F), fit speeds (N,), true futures in the walker's frame (N, PRED, 2)) of every
    window of one file seen with one noise draw (module doc); ``leave_out`` (first, last frame index):
    no window that shares a frame with that stretch (blocked evaluation, ``blocked``); ``scale``: the
    walks scaled by that factor (the same paths walked that much faster) before the detection noise,
    which is drawn afresh for each scale (``SCALES``)."""
    from agents.lib.perception.tracking import Detection, observer_tracker
    from tools.prediction_eval import noisy_annotations, read_annotations, windows

    data = read_annotations(path, DT)
    if scale != 1.0:
        data = replace(data, people=[{pid: (x * scale, y * scale) for pid, (x, y) in frame.items()}
                                     for frame in data.people])
    rng = np.random.default_rng(seed if scale == 1.0 else [seed, round(scale * 1000)])
    noisy = noisy_annotations(data, noise, rng)
    by_start: dict[int, list[int]] = {}
    for start, pid in windows(data, OBS + PRED):
        if leave_out is None or start + OBS + PRED - 1 < leave_out[0] or start > leave_out[1]:
            by_start.setdefault(start, []).append(pid)
    feats, speeds, futures = [], [], []
    for start, pids in by_start.items():
        tracker = observer_tracker(noise, learned=False)
        for k in range(start, start + OBS):
            tracker.update(k * DT, [Detection(str(pid), x, y, 0.0) for pid, (x, y) in sorted(noisy[k].items())])
        now = (start + OBS - 1) * DT
        inputs = tracker.model_inputs([str(pid) for pid in pids], now)
        for pid in pids:
            if str(pid) not in inputs:
                continue
            f, vx, vy = inputs[str(pid)]
            track = tracker.tracks[str(pid)]
            speed = float(np.hypot(vx, vy))
            c, s = vx / speed, vy / speed
            future = np.array([data.people[k][pid] for k in range(start + OBS, start + OBS + PRED)]) - (track.x, track.y)
            futures.append(np.stack([future[:, 0] * c + future[:, 1] * s, -future[:, 0] * s + future[:, 1] * c], 1))
            feats.append(f)
            speeds.append(speed)
    return np.array(feats), np.array(speeds), np.array(futures)


def uncorrected(parts: Sequence[tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]]) -> float:
    """The mean error of the fit's constant velocity on ``examples`` (the training's starting point,
    recorded per file in the provenance: a fingerprint of the data and the noise draws)."""
    futures = np.concatenate([u for _, _, u in parts]).copy()
    speeds = np.concatenate([v for _, v, _ in parts])
    futures[:, :, 0] -= speeds[:, None] * np.arange(1, PRED + 1) * DT
    return round(float(np.sqrt((futures ** 2).sum(axis=2)).mean()), 5)


def fit(features: NDArray[np.float64], speeds: NDArray[np.float64], futures: NDArray[np.float64], hidden: int,
        weight_decay: float, seed: int, iterations: int,
        mirror: bool = True) -> tuple[dict[str, NDArray[np.float64]], dict[str, float]]:
    """The network's parameters (module doc) and the loss before (no correction) and after; with
    ``mirror`` every example also seen in a mirror (``walker_model.mirrored``: a left turn is a right
    turn mirrored)."""
    from scipy.optimize import minimize

    from agents.lib.perception.walker_model import mirrored

    if mirror:
        flipped = futures.copy()
        flipped[:, :, 1] *= -1.0
        features, speeds, futures = (np.concatenate([features, mirrored(features)]), np.concatenate([speeds, speeds]),
                                     np.concatenate([futures, flipped]))
    mean, scale = features.mean(axis=0), features.std(axis=0) + 1e-6
    z = (features - mean) / scale
    t = np.arange(1, PRED + 1) * DT
    residual = futures.copy()
    residual[:, :, 0] -= speeds[:, None] * t[None, :]             # what constant velocity misses
    n, d = z.shape
    shapes = [(d, hidden), (hidden,), (hidden, 2), (2,)]
    sizes = [int(np.prod(s)) for s in shapes]

    def unpack(w: NDArray[np.float64]) -> list[NDArray[np.float64]]:
        out, i = [], 0
        for shape, size in zip(shapes, sizes, strict=True):
            out.append(w[i:i + size].reshape(shape))
            i += size
        return out

    def loss(w: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
        w1, b1, w2, b2 = unpack(w)
        h = np.tanh(z @ w1 + b1)
        out = h @ w2 + b2                                            # (n, 2) velocity correction
        e = out[:, None, :] * t[None, :, None] - residual            # (n, PRED, 2)
        norm = np.sqrt((e ** 2).sum(axis=2) + 1e-6)
        value = norm.mean() + weight_decay * ((w1 ** 2).sum() + (w2 ** 2).sum())
        g_out = ((e / norm[..., None]) * t[None, :, None]).sum(axis=1) / (n * PRED)
        g_w2 = h.T @ g_out + 2 * weight_decay * w2
        g_h = g_out @ w2.T * (1 - h ** 2)
        g_w1 = z.T @ g_h + 2 * weight_decay * w1
        return float(value), np.concatenate([g_w1.ravel(), g_h.sum(0), g_w2.ravel(), g_out.sum(0)])

    rng = np.random.default_rng(seed)
    start = np.concatenate([rng.normal(0.0, 1.0 / np.sqrt(d), d * hidden), np.zeros(hidden), np.zeros(hidden * 2),
                            np.zeros(2)])
    result = minimize(loss, start, jac=True, method="L-BFGS-B", options={"maxiter": iterations})
    w1, b1, w2, b2 = unpack(result.x)
    before = float(np.sqrt((residual ** 2).sum(axis=2)).mean())
    return ({"mean": mean, "scale": scale, "w1": w1, "b1": b1, "w2": w2, "b2": b2},
            {"ade_m_without_model": round(before, 5), "loss_with_model": round(float(result.fun), 5)})


def train(files: Sequence[Path], noise: float = 0.02, noise_seeds: Sequence[int] = (1, 2), seed: int = 0,
          hidden: int = 16, weight_decay: float = 0.01, iterations: int = 400, max_correction: float = 0.4,
          command: str = "", scales: Sequence[float] = SCALES) -> dict[str, object]:
    """The model file's JSON (walker_model.py's format) trained on ``files`` (module doc), each walk
    also scaled by ``scales`` (``SCALES``; the provenance's per-file figures are the unscaled ones)."""
    from agents.lib.perception.tracking import STILL_MPS
    from agents.lib.perception.walker_model import WalkerModel

    per_file = [[examples(path, noise, s) for s in noise_seeds] for path in files]
    parts = [part for mine in per_file for part in mine] + \
        [examples(path, noise, s, scale=k) for path in files for s in noise_seeds for k in scales if k != 1.0]
    features = np.concatenate([p[0] for p in parts])
    if len(features) == 0:
        from tools.prediction_eval import PedestrianFileError

        raise PedestrianFileError(f"{', '.join(p.name for p in files)}: no window to train on (no walker seen for "
                                  f"{OBS + PRED} consecutive frames at {noise:g} m of noise)")
    params, losses = fit(features, np.concatenate([p[1] for p in parts]), np.concatenate([p[2] for p in parts]),
                         hidden, weight_decay, seed, iterations)
    provenance = {
        "command": command,
        "files": [{"name": p.name, "sha256": hashlib.sha256(p.read_bytes()).hexdigest(),
                   "examples": sum(len(f) for f, _, _ in mine), "ade_m_without_model": uncorrected(mine)}
                  for p, mine in zip(files, per_file, strict=True)],
        "seed": seed, "noise_m": noise, "noise_seeds": list(noise_seeds), "hidden": hidden,
        "weight_decay": weight_decay, "iterations": iterations, "mirrored": True,
        "scales": [float(k) for k in scales], "examples": sum(len(f) for mine in per_file for f, _, _ in mine),
        "training_examples": 2 * int(len(features)),
        "question": f"observe {OBS} x {DT} s, predict {PRED} x {DT} s", **losses}
    model = WalkerModel(min_speed_mps=STILL_MPS, max_correction_mps=max_correction, noise_m=noise,
                        provenance=provenance, **params)
    return model.to_json()


def blocked(files: Sequence[Path], folds: int = 5, noise: float = 0.02, noise_seeds: Sequence[int] = (1, 2),
            seed: int = 0, **options: float) -> dict[str, object]:
    """In-file figures without the answers in the training set: each file cut into ``folds``
    stretches of frames; each stretch is evaluated (``chronav predict evaluate``'s ``evaluate``, 2 cm
    noise, seed 0, on the windows inside it) with a model trained on the other files and on the
    windows of this file that share no frame with it.  Per file: the window-weighted ADE/FDE over
    the window-weighted constant-velocity baseline, and the same without the model (the fit's
    velocity: ``fit_only``) on the same windows."""
    from agents.lib.perception.tracking import STILL_MPS
    from agents.lib.perception.walker_model import WalkerModel
    from tools.prediction_eval import Annotations, evaluate, read_annotations

    out: dict[str, object] = {}
    for path in files:
        data = read_annotations(path, DT)
        edges = np.linspace(0, len(data.frames), folds + 1).astype(int)
        totals = np.zeros(7)
        for a, b in zip(edges[:-1], edges[1:], strict=True):
            parts = [examples(p, noise, s, (a, b - 1) if p == path else None, k) for p in files for s in noise_seeds
                     for k in SCALES]
            params, _ = fit(np.concatenate([q[0] for q in parts]), np.concatenate([q[1] for q in parts]),
                            np.concatenate([q[2] for q in parts]), int(options.get("hidden", 16)),
                            float(options.get("weight_decay", 0.01)), seed, int(options.get("iterations", 400)))
            model = WalkerModel(min_speed_mps=STILL_MPS, max_correction_mps=float(options.get("max_correction", 0.4)),
                                noise_m=noise, provenance={}, **params)
            piece = Annotations(data.name, data.frames[a:b], data.people[a:b])
            zero = WalkerModel(min_speed_mps=STILL_MPS, max_correction_mps=0.0, noise_m=noise, provenance={}, **params)
            try:
                r = evaluate(piece, noise=noise, seed=0, model=model)
                z = evaluate(piece, noise=noise, seed=0, model=zero)
            except ValueError:
                continue                     # a stretch too short for a window
            totals += np.array([r.ade, r.fde, r.cv_ade, r.cv_fde, z.ade, z.fde, 1.0]) * r.tracks
        ade, fde, cv_ade, cv_fde, z_ade, z_fde, n = totals
        out[path.name] = {"ade_over_cv": round(ade / cv_ade, 4), "fde_over_cv": round(fde / cv_fde, 4),
                          "fit_only_ade_over_cv": round(z_ade / cv_ade, 4),
                          "fit_only_fde_over_cv": round(z_fde / cv_fde, 4), "windows": int(n)}
    return out


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="*", type=Path, default=DEFAULT_FILES)
    parser.add_argument("--out", type=Path, default=REPO / "agents" / "lib" / "perception" / "walker_model.json")
    parser.add_argument("--noise", type=float, default=0.02)
    parser.add_argument("--noise-seeds", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--hidden", type=int, default=16)
    parser.add_argument("--weight-decay", type=float, default=0.01)
    parser.add_argument("--iterations", type=int, default=400)
    parser.add_argument("--max-correction", type=float, default=0.4)
    parser.add_argument("--blocked", type=int, default=0, metavar="K",
                        help="instead of training: in-file figures, each file in K stretches, each evaluated "
                             "by a model trained without it (blocked)")
    args = parser.parse_args(argv)
    if not args.files:
        raise SystemExit("no pedestrian files given and none in scenes/data/pedestrians")
    sys.path.insert(0, str(REPO))
    if args.blocked:
        print(json.dumps(blocked(args.files, args.blocked, args.noise, args.noise_seeds, args.seed, hidden=args.hidden,
                                 weight_decay=args.weight_decay, iterations=args.iterations,
                                 max_correction=args.max_correction)))
        return
    command = shlex.join(["tools/train_prediction.py", *(sys.argv[1:] if argv is None else argv)])
    model = train(args.files, args.noise, args.noise_seeds, args.seed, args.hidden, args.weight_decay,
                  args.iterations, args.max_correction, command)
    args.out.write_text(json.dumps(model, indent=1) + "\n", encoding="utf-8")
    print(json.dumps({"out": str(args.out), **model["provenance"]}))        # type: ignore[dict-item]


if __name__ == "__main__":
    main()
