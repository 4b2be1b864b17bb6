"""``chronav predict evaluate FILE...``: the deployed people prediction measured on real pedestrians.

Why a command: the social map's prediction is the navigation's view of the future, and the only
honest way to know it is good is the trajectory-prediction literature's own benchmark, run on the
code that is deployed (tools/prediction_eval.py says how), with the constant-velocity baseline
computed in the same run.  docs/prediction.md gives the figures and how to read them.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer


def _positive(value: float, option: str) -> float:
    if not (math.isfinite(value) and value > 0):
        raise typer.BadParameter("must be a positive number", param_hint=option)
    return value


def register(app: typer.Typer) -> None:
    predict_app = typer.Typer(help="Measure how well chronav predicts where people will be.",
                              no_args_is_help=True)
    app.add_typer(predict_app, name="predict")

    @predict_app.command("train")
    def train_cmd(
        files: list[Path] | None = typer.Argument(None, help="ETH/UCY text files or runs' people.csv to learn "
                                                            "from; default: the two UCY sequences shipped in "
                                                            "scenes/data/pedestrians", show_default=False),
        out: Path = typer.Option(..., "--out", help="the model file to write (JSON)"),
        seed: int = typer.Option(0, "--seed", min=0, max=2**31 - 1, help="seed of the network's starting weights"),
        noise: float | None = typer.Option(None, "--noise", help="detection noise the model is trained for, m; "
                                                                "default: the live observer's, 0.02",
                                           show_default=False),
        noise_seeds: str = typer.Option("1,2", "--noise-seeds", help="comma-separated seeds of the noise draws "
                                                                     "(each a copy of the data seen through other noise)"),
        iterations: int = typer.Option(400, "--iterations", min=1, max=100_000, help="L-BFGS iterations"),
        dt: float = typer.Option(0.4, "--dt", help="seconds between frames (people.csv: the grid it is taken on)"),
        force: bool = typer.Option(False, "--force", help="overwrite --out"),
        as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
    ) -> None:
        """Train the walker model (the tracker's learned velocity correction, docs/prediction.md) on
        a site's own recordings: seeded and reproducible, the training data's provenance (files and
        sha256, windows, seeds, command) in the model file.  Use it with --model in launch, evaluate
        and predict evaluate."""
        import shlex
        import sys

        from agents.lib.perception.tracking import OBSERVER_NOISE_M
        from tools.prediction_eval import PedestrianFileError, shipped_pedestrian_files
        from tools.train_prediction import DT, train

        if not math.isclose(_positive(dt, "--dt"), DT):
            raise typer.BadParameter(f"the walker model reads a {DT:g} s grid; other steps are not supported yet",
                                     param_hint="--dt")
        noise = OBSERVER_NOISE_M if noise is None else noise
        if not (math.isfinite(noise) and 0 < noise <= 1.0):
            raise typer.BadParameter("must be above 0 and at most 1 m (a perfect detector needs no model)",
                                     param_hint="--noise")
        try:
            seeds = tuple(int(v) for v in noise_seeds.split(",") if v.strip())
        except ValueError:
            raise typer.BadParameter("comma-separated whole numbers, e.g. 1,2", param_hint="--noise-seeds") from None
        if not seeds or len(seeds) > 20 or any(v < 0 for v in seeds):
            raise typer.BadParameter("1 to 20 seeds of 0 or more", param_hint="--noise-seeds")
        if out.exists() and not force:
            typer.echo(f"error: {out} exists; pass --force to overwrite it", err=True)
            raise typer.Exit(2)
        files = files or shipped_pedestrian_files()
        command = shlex.join(["chronav", *sys.argv[1:]]) if sys.argv[1:3] == ["predict", "train"] else \
            shlex.join(["chronav", "predict", "train", *map(str, files), "--out", str(out), "--seed", str(seed)])
        try:
            model = train(files, noise=noise, noise_seeds=seeds, seed=seed, iterations=iterations, command=command)
        except PedestrianFileError as exc:
            typer.echo(f"error: {exc}", err=True)
            raise typer.Exit(2) from None
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
            out.write_text(json.dumps(model, indent=1) + "\n", encoding="utf-8")
        except OSError as exc:
            typer.echo(f"error: cannot write {out}: {exc.strerror or exc}", err=True)
            raise typer.Exit(2) from None
        provenance = model["provenance"]
        if as_json:
            typer.echo(json.dumps({"out": str(out), **provenance}))       # type: ignore[dict-item]
            return
        typer.echo(f"{out}: walker model trained on {provenance['examples']} walker windows of "   # type: ignore[index]
                   f"{len(files)} file(s) at {noise:g} m noise, seed {seed}; use it with --model {out}")

    @predict_app.command("evaluate")
    def evaluate_cmd(
        files: list[Path] | None = typer.Argument(None, help="ETH/UCY text files ('frame id x y' a line, frames "
                                                            "0.4 s apart) or a run's people.csv; default: the two "
                                                            "UCY sequences shipped in scenes/data/pedestrians",
                                                  show_default=False),
        obs: int = typer.Option(8, "--obs", min=2, max=1000, help="observed steps (the tracker sees these)"),
        pred: int = typer.Option(12, "--pred", min=1, max=1000, help="predicted steps"),
        dt: float = typer.Option(0.4, "--dt", help="seconds between frames"),
        noise: float | None = typer.Option(None, "--noise", help="detection noise, m (standard deviation per "
                                                                "axis); default: the live observer's, 0.02",
                                           show_default=False),
        seed: int = typer.Option(0, "--seed", help="seed of the detection noise"),
        scene: str | None = typer.Option(None, "--scene", help="for a run's people.csv: the run's scene, so the "
                                                              "prediction knows its walls, doors and agenda"),
        agenda: bool = typer.Option(True, "--agenda/--no-agenda", help="with --scene: use the agenda (where people "
                                                                       "whose activity is near are going)"),
        min_speed: float = typer.Option(0.0, "--min-speed", help="only windows whose person walked at least this "
                                                                 "fast (m/s, observed steps, true positions)"),
        detect_every: int = typer.Option(1, "--detect-every", min=1, max=100,
                                         help="detections per frame (interpolated between frames): 4 on "
                                              "0.4 s frames is the observer's 10 Hz"),
        model: Path | None = typer.Option(None, "--model", help="a walker model file (tools/train_prediction.py) "
                                                                "instead of the shipped one: cross-file figures"),
        predictor: str = typer.Option("chronav", "--predictor",
                                      help="a registered people predictor (`chronav plugins` lists them)"),
        as_json: bool = typer.Option(False, "--json", help="print one JSON object"),
    ) -> None:
        """ADE/FDE of the deployed tracker + prediction per file, beside the constant-velocity
        baseline on the true positions (same windows, same run) and the ratio (< 1: better)."""
        from agents.lib.perception.tracking import OBSERVER_NOISE_M
        from tools.prediction_eval import (PedestrianFileError, SceneContext, evaluate_files, shipped_pedestrian_files,
                                           summary)

        _positive(dt, "--dt")
        noise_origin = "given" if noise is not None else "the live observer's default"
        noise = OBSERVER_NOISE_M if noise is None else noise
        files = files or shipped_pedestrian_files()
        if not (math.isfinite(noise) and 0 <= noise <= 1.0):
            raise typer.BadParameter("must be between 0 and 1 m", param_hint="--noise")
        if not (math.isfinite(min_speed) and min_speed >= 0):
            raise typer.BadParameter("must be a speed of 0 m/s or more", param_hint="--min-speed")
        context = None
        if scene is not None:
            from scenes.loader import resolve_scene_path
            from scenes.yamlio import SourceError

            try:
                context = SceneContext(resolve_scene_path(scene), agenda=agenda)
            except (SourceError, OSError) as exc:
                typer.echo(f"error: {exc}", err=True)
                raise typer.Exit(2) from None
        from agents.lib.perception.walker_model import WalkerModelError, load
        from agents.lib.registry import RefusedExtension, UnknownExtension
        from agents.lib.socialmap.predictors import predictor as lookup_predictor

        try:
            lookup_predictor(predictor)
        except (UnknownExtension, RefusedExtension) as exc:
            raise typer.BadParameter(str(exc), param_hint="--predictor") from None
        try:
            walker = load(model) if model is not None else None
            results = evaluate_files(files, obs=obs, pred=pred, dt=dt, noise=noise, seed=seed, context=context,
                                     min_speed=min_speed, detect_every=detect_every, model=walker,
                                     predictor=predictor)
        except (PedestrianFileError, WalkerModelError, ValueError) as exc:
            typer.echo(f"error: {exc}", err=True)
            raise typer.Exit(2) from None
        report = summary(results)
        report["noise_m"] = noise
        if as_json:
            typer.echo(json.dumps(report))
            return
        known = "" if context is None else f"; context: {scene} walls{' + agenda' if agenda else ''}"
        known += f"; walkers at {min_speed:g} m/s or more" if min_speed > 0 else ""
        known += f"; {detect_every} detections per frame" if detect_every > 1 else ""
        known += f"; walker model {model}" if model is not None else ""
        known += f"; predictor {predictor}" if predictor != "chronav" else ""
        typer.echo(f"observe {obs} x {dt:g} s, predict {pred} x {dt:g} s, "
                   f"detection noise {noise:g} m ({noise_origin}; seed {seed}){known}")
        typer.echo(f"{'file':28s} {'windows':>8s} {'ADE m':>7s} {'FDE m':>7s} {'CV ADE':>7s} {'CV FDE':>7s} "
                   f"{'ADE/CV':>7s} {'FDE/CV':>7s} {'ADE/CVd':>7s} {'FDE/CVd':>7s}")
        for name, r in results.items():
            typer.echo(f"{name:28s} {r.tracks:8d} {r.ade:7.3f} {r.fde:7.3f} {r.cv_ade:7.3f} {r.cv_fde:7.3f} "
                       f"{r.ade / r.cv_ade if r.cv_ade else math.nan:7.3f} "
                       f"{r.fde / r.cv_fde if r.cv_fde else math.nan:7.3f} "
                       f"{r.ade / r.cv_det_ade if r.cv_det_ade else math.nan:7.3f} "
                       f"{r.fde / r.cv_det_fde if r.cv_det_fde else math.nan:7.3f}")
        typer.echo(f"average over the files: ADE/CV {report['ade_over_cv']}, FDE/CV {report['fde_over_cv']} "
                   "(CV: constant velocity from the last true step); "
                   f"ADE/CVd {report['ade_over_cv_same_detections']}, FDE/CVd {report['fde_over_cv_same_detections']} "
                   "(CVd: constant velocity from the same last two noisy detections)")
