"""`chronav evaluate SCENE...`: a reproducible study of planners across scenes and seeds.

Why a command and not a script: researchers compare planners on the same scenes with many seeds;
the study must be one line to run again, give the same numbers (a seed fixes the simulated world,
the clock runs in lockstep with the controller), and say what produced it.  The pieces:

- tools/evaluate/sweep.py: scene x planner x seed runs, each in-process in lockstep (``--mode
  in-process``, the default; tools/inprocess.py, tools/evaluate/pool.py) or a full isolated launch
  (``--mode launch``), on this machine (``--jobs J``, all cores by default) or a Dask cluster
  (``--executor dask://HOST:PORT``), with a ledger for ``--resume``;
- tools/evaluate/table.py: one row per mission with every metric of ``chronav metrics``;
- tools/evaluate/stats.py, figures.py, report.py: tables, tests, plots, report.
"""

from __future__ import annotations

import json
import math
import shlex
import sys
import time
from datetime import datetime
from pathlib import Path
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import typer

from tools.plain import WHOLE_LINE
from tools.walker_models import checked_model

if TYPE_CHECKING:
    from tools.evaluate.sweep import RunSpec

SWEEP_FILE = "sweep.json"


class EvaluateError(Exception):
    """A study that cannot start as asked; the message says what to change."""


def _check_extras() -> None:
    """matplotlib and pyarrow come with chronav's `eval` extra: say so before launching anything."""
    import importlib.util

    missing = [name for name in ("matplotlib", "pyarrow") if importlib.util.find_spec(name) is None]
    if missing:
        raise EvaluateError(f"chronav evaluate needs {' and '.join(missing)}: install chronav's eval extra "
                            "(pip install -e '.[eval]', which make test and make demo do)")


def parse_planners(text: str | None) -> list[str]:
    """--planners A,B (default: every installed planner), each checked now: an unknown name is an
    error listing the known ones; a plug-in that cannot be loaded is refused with a warning naming
    it, its package and why, and the study runs without it."""
    from agents.lib.planning.planners import planner, planner_names

    return _axis("--planners", "planner", text, planner_names(), planner, "social,baseline")


def parse_controllers(text: str | None) -> list[str]:
    """--controllers A,B (default: chronav's elastic band alone), each checked now as --planners are:
    built once for a generic robot, so a factory that fails or breaks the protocol is refused."""
    from agents.lib.control.controllers import controller
    from agents.lib.control.protocol import RobotLimits
    from tools.evaluate.sweep import DEFAULT_CONTROLLER

    generic = RobotLimits(radius_m=0.3, max_speed_mps=0.6, max_angular_speed_radps=1.2)
    return _axis("--controllers", "controller", text, (DEFAULT_CONTROLLER,), lambda name: controller(name, generic),
                 "elastic_band,orca")


def _axis(option: str, kind: str, text: str | None, installed: tuple[str, ...], load: Callable[[str], object],
          example: str) -> list[str]:
    from agents.lib.registry import RefusedExtension, UnknownExtension

    names = list(installed) if text is None else [name.strip() for name in text.split(",") if name.strip()]
    if not names:
        raise EvaluateError(f"{option}: name at least one {kind}, e.g. {example}")
    if len(set(names)) != len(names):
        raise EvaluateError(f"{option} {text}: a {kind} is named twice")
    usable = []
    for name in names:
        try:
            load(name)
        except UnknownExtension as exc:
            raise EvaluateError(f"{option}: {exc}") from None
        except RefusedExtension as exc:
            print(f"warning: {exc}; the study runs without it", file=sys.stderr)
            continue
        usable.append(name)
    if not usable:
        raise EvaluateError(f"{option}: every {kind} named was refused (see the warnings above)")
    return usable


def resolve_scenes(names: list[str]) -> list[Path]:
    """Each scene's file, loaded once to fail early with the file, line and key of an error."""
    from agents.world.scene_world import load_world
    from scenes.yamlio import SourceError

    paths = []
    for name in names:
        try:
            paths.append(load_world(name).path.resolve())
        except SourceError as exc:
            raise EvaluateError(str(exc)) from None
    stems = [p.stem for p in paths]
    if len(set(stems)) != len(stems):
        raise EvaluateError("two scenes share a file name (" + ", ".join(sorted({s for s in stems if stems.count(s) > 1}))
                            + "); the table names scenes by file name: rename one")
    return paths


def prepare_out_dir(out: Path | None, resume: bool) -> Path:
    from tools.evaluate.sweep import LEDGER

    if out is None:
        if resume:
            raise EvaluateError("--resume continues the sweep in --out DIR: give that directory")
        out = Path.cwd() / "evaluations" / datetime.now().strftime("%Y%m%d-%H%M%S")
    out = out.absolute()
    if (out / LEDGER).exists() and not resume:
        raise EvaluateError(f"{out} already holds a sweep ({LEDGER}); continue it with --resume, or choose "
                            "another --out")
    if resume and not (out / LEDGER).exists():
        raise EvaluateError(f"--resume: {out} holds no sweep to continue (no {LEDGER}); run without --resume")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise EvaluateError(f"cannot create {out}: {exc.strerror}; choose another --out") from None
    return out


def run_sweep(specs: list[Any], executor: Any, out_dir: Path, timeout_s: float,
              on_result: Any = None) -> tuple[list[dict[str, Any]], bool]:
    """Run ``specs`` on ``executor``; each result goes to the ledger as it arrives.  Returns the
    results and whether the sweep was interrupted (Ctrl-C: the runs under way are stopped)."""
    from tools.evaluate.sweep import append_ledger

    results: list[dict[str, Any]] = []
    stream = executor.results(specs, out_dir / "runs", timeout_s)
    try:
        for result in stream:
            if not result.get("interrupted"):
                append_ledger(out_dir, result)
            results.append(result)
            if on_result is not None:
                on_result(result)
    except KeyboardInterrupt:
        executor.interrupt()
        stream.close()
        return results, True
    return results, any(r.get("interrupted") for r in results)


class _Progress:
    """Progress per planner with its ETA (a rich bar per planner on a terminal; one plain line per
    finished run otherwise).  Why per planner: planners differ in cost per run (a blocked social
    planner waits, a baseline drives straight through), so one overall rate mispredicts the end."""

    def __init__(self, specs: list[Any], quiet: bool) -> None:
        from rich.console import Console

        self.started = time.monotonic()
        self.total = len(specs)
        self.done = 0
        self.planned: dict[str, int] = {}
        for spec in specs:
            self.planned[spec.method] = self.planned.get(spec.method, 0) + 1
        self.finished: dict[str, int] = dict.fromkeys(self.planned, 0)
        self.busy_s: dict[str, float] = dict.fromkeys(self.planned, 0.0)
        self.console = Console(stderr=True)
        self.bar = None
        self.quiet = quiet
        if not quiet and sys.stderr.isatty():
            from rich.progress import (BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn,
                                       TimeRemainingColumn)

            self.bar = Progress(TextColumn("[bold]{task.fields[planner]:>10}[/bold]"), BarColumn(),
                                MofNCompleteColumn(), TextColumn("elapsed"), TimeElapsedColumn(),
                                TextColumn("ETA"), TimeRemainingColumn(), TextColumn("{task.description}"),
                                console=self.console)
            self.tasks = {planner: self.bar.add_task("", total=n, planner=planner)
                          for planner, n in self.planned.items()}

    def __enter__(self) -> _Progress:
        if self.bar is not None:
            self.bar.start()
        return self

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.stop()

    def eta_s(self, planner: str | None = None) -> float:
        """Seconds left: for one planner, from its own mean run time (the sweep's parallelism
        included through the overall rate); for the sweep, from the overall rate."""
        elapsed = time.monotonic() - self.started
        if self.done == 0:
            return math.nan
        per_run = elapsed / self.done       # wall seconds per finished run, all planners, all jobs
        if planner is None:
            return per_run * (self.total - self.done)
        mean_all = sum(self.busy_s.values()) / self.done
        mean = self.busy_s[planner] / self.finished[planner] if self.finished[planner] else mean_all
        scale = mean / mean_all if mean_all > 0 else 1.0
        return per_run * scale * (self.planned[planner] - self.finished[planner])

    def advance(self, result: dict[str, Any]) -> None:
        from tools.evaluate.sweep import RunSpec

        self.done += 1
        spec = RunSpec.from_dict(result["spec"])
        wall = float(result.get("wall_s", 0.0))
        if spec.method in self.finished:
            self.finished[spec.method] += 1
            self.busy_s[spec.method] += wall
        what = f"{spec.label}: {result.get('outcome')} ({wall:.1f} s)"
        if self.bar is not None:
            if spec.method in self.tasks:
                self.bar.update(self.tasks[spec.method], advance=1, description=what)
            return
        if self.quiet:
            return
        elapsed = time.monotonic() - self.started
        planner_eta = self.eta_s(spec.method) if spec.method in self.planned else math.nan
        self.console.print(f"[evaluate] {self.done}/{self.total} {what}; {spec.method} "
                           f"{self.finished.get(spec.method, 0)}/{self.planned.get(spec.method, 0)}, "
                           f"ETA {planner_eta / 60:.1f} min; all: elapsed {elapsed / 60:.1f} min, "
                           f"ETA {self.eta_s() / 60:.1f} min", highlight=False, markup=False, soft_wrap=True)


MAX_SEEDS = 10_000   # seeds per scene and planner in one study (docs/limits.md)
#: what a study run with --no-figures draws (tools/evaluate/figures.py all_figures' keys)
NO_FIGURES: dict[str, list[Path]] = {"paths": [], "r_of_t": [], "boxes": []}


def evaluate(scenes: list[str], *, planners: str | None, seeds: int, first_seed: int, jobs: int | None,
             out: Path | None, executor_text: str, resume: bool, timeout_s: float, quiet: bool, command: str,
             mode: str = "in-process", record: bool = True, controllers: str | None = None,
             model: Path | None = None, draw_figures: bool = True) -> dict[str, Any]:
    """The whole study; returns what ``--json`` prints (``model``: the observer's walker model file;
    ``draw_figures=False``: the report without its figures, ``--no-figures``)."""
    from tools.evaluate.figures import all_figures
    from tools.evaluate.report import provenance, write_report
    from tools.evaluate.executors import parse_executor
    from tools.evaluate.sweep import DEFAULT_CONTROLLER, method_label, plan_sweep, read_ledger
    from tools.evaluate.table import write_table

    _check_extras()
    chosen = parse_planners(planners)
    drivers = parse_controllers(controllers)
    _warn_refused_metrics()
    _check_seeds_and_timeout(seeds, timeout_s)
    scene_paths = resolve_scenes(scenes)
    out_dir = prepare_out_dir(out, resume)
    seed_list = list(range(first_seed, first_seed + seeds))
    specs = plan_sweep(scene_paths, chosen, seed_list, drivers, str(model.resolve()) if model is not None else "")
    try:
        executor = parse_executor(executor_text, jobs, mode, record)
    except ValueError as exc:
        raise EvaluateError(str(exc)) from None
    jobs = getattr(executor, "jobs", jobs)
    prov = {**provenance(scene_paths, chosen, seed_list, executor_text, jobs or 0, command), "mode": mode, "record": record,
            "controllers": drivers, "figures": draw_figures}
    (out_dir / SWEEP_FILE).write_text(json.dumps({**prov, "runs": [s.to_dict() for s in specs]}, indent=2))
    earlier = read_ledger(out_dir) if resume else {}
    todo = [s for s in specs if s.key not in earlier]
    started = time.monotonic()
    try:
        with _Progress(todo, quiet) as progress:
            new, interrupted = run_sweep(todo, executor, out_dir, timeout_s, on_result=progress.advance)
    finally:
        close = getattr(executor, "close", None)
        if close is not None:
            close()
    sweep_wall_s = time.monotonic() - started
    ordered, rows, pending = _merge_runs(specs, earlier, new)
    parquet, csv = write_table(rows, out_dir)
    from agents.world.offline import SceneMaps

    maps = {path.stem: SceneMaps.load(path) for path in scene_paths}
    # The report groups by planner x controller: each pair is one method, named by method_label
    # (the planner alone with the default controller, so a study without --controllers reads as before).
    methods = [method_label(p, c) for p in chosen for c in drivers]
    shown = [{**row, "planner": method_label(row["planner"], row.get("controller") or DEFAULT_CONTROLLER)}
             for row in rows]
    figures = all_figures(shown, maps, out_dir, methods) if draw_figures else NO_FIGURES
    report = write_report(out_dir, shown, ordered, prov, figures, methods, pending=pending)
    launched = [r for r in new if not r.get("interrupted")]
    wanted = {s.key for s in specs}
    return {"out": str(out_dir), "report": str(report), "table": {"parquet": str(parquet), "csv": str(csv)},
            "runs": len(specs), "launched": len(launched), "resumed": len(earlier.keys() & wanted),
            "ok": sum(1 for r in ordered if r.get("ok")), "failed": _failures(ordered), "pending": pending,
            "refused_missions": int(sum(r.get("refused") or 0 for r in rows)),
            "interrupted": interrupted, "sweep_wall_s": round(sweep_wall_s, 2),
            "runs_per_min": round(len(launched) / (sweep_wall_s / 60.0), 3) if launched and sweep_wall_s > 0 else None,
            "mode": mode, "jobs": jobs, "requeued": list(getattr(executor, "requeued", [])),
            "figures": {k: [str(p) for p in v] for k, v in figures.items()}}


def _check_seeds_and_timeout(seeds: int, timeout_s: float) -> None:
    """--seeds within 1..MAX_SEEDS and a valid --timeout, before anything is planned or written."""
    from tools.launch import check_timeout, LaunchError

    if seeds < 1:
        raise EvaluateError("--seeds: give at least 1")
    if seeds > MAX_SEEDS:   # the sweep is planned up front: 10^12 seeds filled memory
        raise EvaluateError(f"--seeds {seeds:,}: give 1 to {MAX_SEEDS:,} (docs/limits.md)")
    try:
        check_timeout(timeout_s)
    except LaunchError as exc:
        raise EvaluateError(str(exc)) from None


def _merge_runs(specs: list[RunSpec], earlier: dict[str, dict[str, Any]], new: list[dict[str, Any]]
                ) -> tuple[list[dict[str, Any]], list[dict[str, Any]], int]:
    """The study's runs in sweep order (a finished new result replaces a resumed one, an unfinished
    one only fills a gap), their metric rows, and how many runs are not finished."""
    from tools.evaluate.sweep import finished

    wanted = {s.key for s in specs}
    runs = {key: r for key, r in earlier.items() if key in wanted}
    for result in new:
        if finished(result) or result["key"] not in runs:
            runs[result["key"]] = result
    ordered = [runs[s.key] for s in specs if s.key in runs]
    rows = [row for run in ordered if finished(run) for row in run["rows"]]
    pending = sum(1 for s in specs if s.key not in runs or not finished(runs[s.key]))
    return ordered, rows, pending


def _warn_refused_metrics() -> None:
    """A metric plug-in that cannot be loaded is named now; the study measures without it."""
    from agents.lib.metrics.registered import usable_metrics

    for refused in usable_metrics()[1]:
        print(f"warning: {refused}; the study measures without it", file=sys.stderr)


def _failures(ordered: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Each run that did not complete every mission: its label, outcome and error."""
    from tools.evaluate.sweep import RunSpec

    return [{"run": RunSpec.from_dict(r["spec"]).label, "outcome": r.get("outcome"), "error": r.get("error")}
            for r in ordered if not r.get("ok")]


def evaluate_command(
        scenes: list[str] = typer.Argument(..., help="scene files or names in scenes/"),
        controllers: str = typer.Option(None, "--controllers", show_default=False,
                                        help="comma-separated registered local controllers, an axis beside "
                                             "--planners (default: elastic_band; `chronav plugins` lists them)"),
        planners: str = typer.Option(None, "--planners", show_default=False,
                                     help="comma-separated registered planners, e.g. social,baseline "
                                          "(default: every installed one; `chronav plugins` lists them)"),
        seeds: int = typer.Option(3, "--seeds", help="seeds per scene and planner (1, 2, ... N)"),
        first_seed: int = typer.Option(1, "--first-seed", help="the first seed"),
        jobs: int = typer.Option(None, "--jobs", "-j", min=1, show_default=False,
                                 help="runs at once on this machine (--executor local; default: every core)"),
        mode: str = typer.Option("in-process", "--mode",
                                 help="in-process: the agents in one process, in lockstep (fast); launch: each "
                                      "run a full launch of the agents as processes (the reference)"),
        no_record: bool = typer.Option(False, "--no-record",
                                       help="no Rerun recording per run (faster; the report then links none)"),
        no_figures: bool = typer.Option(False, "--no-figures",
                                        help="a report without figures (the table, summary and tests only; "
                                             "a figure per metric costs ~0.1 s of CPU, 85 on a crowd scene)"),
        out: Path = typer.Option(None, "--out", help="the study's directory (default ./evaluations/<date-time>)"),
        executor: str = typer.Option("local", "--executor", help="local, or dask://HOST:PORT of a Dask scheduler"),
        resume: bool = typer.Option(False, "--resume", help="continue the interrupted sweep in --out"),
        timeout: float = typer.Option(900.0, "--timeout", help="wall-clock limit of each run in seconds"),
        model: Path = typer.Option(None, "--model", help="walker model file for the human observer (chronav "
                                                         "predict train; default: the shipped one)"),
        as_json: bool = typer.Option(False, "--json", help="one JSON object on stdout")) -> None:
    """Run every SCENE x planner x seed, then write the table and DIR/report.html.

    Each run is isolated (own graph and run directory under DIR/runs; in launch mode its own
    router and credentials too); both modes compute the same runs. Exit 0 when
    every run completed every mission, 1 when some did not (the report says which), 2 on bad
    input, 130 when interrupted (the finished runs are kept: continue with --resume)."""
    from rich.console import Console

    err = Console(stderr=True)
    command = "chronav " + " ".join(shlex.quote(a) for a in sys.argv[1:])
    try:
        summary = evaluate(scenes, planners=planners, controllers=controllers, seeds=seeds, first_seed=first_seed, jobs=jobs, out=out,
                           executor_text=executor, resume=resume, timeout_s=timeout, quiet=as_json,
                           command=command, mode=mode, record=not no_record, model=checked_model(model),
                           draw_figures=not no_figures)
    except EvaluateError as exc:
        err.print(f"error: {exc}", highlight=False, markup=False, soft_wrap=True)
        raise typer.Exit(2) from None
    if as_json:
        typer.echo(json.dumps(summary))
    else:
        _print_summary(summary, Console())
    if summary["interrupted"]:
        raise typer.Exit(130)
    raise typer.Exit(0 if not summary["failed"] and not summary["pending"] else 1)


def register(app: typer.Typer) -> None:
    app.command("evaluate")(evaluate_command)


def _print_summary(summary: dict[str, Any], out: Any) -> None:
    line = WHOLE_LINE    # paths and messages stay whole
    for failure in summary["failed"]:
        out.print(f"not ok: {failure['run']}: {failure['outcome']}"
                  + (f" ({failure['error']})" if failure.get("error") else ""), **line)
    out.print(f"table: {summary['table']['parquet']} (and .csv)", **line)
    out.print(f"report: {summary['report']}", **line)
    rate = summary.get("runs_per_min")
    speed = f", {rate:.2f} runs/min" if rate is not None and math.isfinite(rate) else ""
    state = "INTERRUPTED" if summary["interrupted"] else "done"
    out.print(f"{state}: {summary['ok']}/{summary['runs']} runs completed every mission "
              f"({summary['launched']} launched, {summary['resumed']} resumed{speed})"
              + (f"; {summary['pending']} to run: add --resume --out {summary['out']}" if summary["pending"] else ""),
              **line)
