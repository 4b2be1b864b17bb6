"""Tune the elastic band gains k_c, k_r by coordinate descent on G = aH + bD + cQ + dP (seed 5.4).

Usage (from the repo root):  python tools/plan/tune_gains.py [--samples 5] [--rounds 4] [--json]
Prints a table (start vs found gains, G, the terms per scenario) and then one JSON object with
the gains found; with --json only the JSON object. Deterministic: same options, same answer.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

import typer

if TYPE_CHECKING:
    from agents.lib.control.tuning import TuningResult

if __package__ in (None, ""):  # run as a script: make the repo root importable
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

app = typer.Typer(add_completion=False, help=__doc__)


@app.command()
def main(
    samples: int = typer.Option(5, min=2, help="values sampled per gain and round"),
    rounds: int = typer.Option(6, min=1, help="maximum rounds of the coordinate descent"),
    max_evaluations: int = typer.Option(60, min=1, help="maximum evaluations of G"),
    start_k_c: float = typer.Option(120.0, help="starting k_c (seed: 120)"),
    start_k_r: float = typer.Option(60.0, help="starting k_r (seed: 60)"),
    k_c_max: float = typer.Option(250.0, help="k_c is searched in [0, k_c_max]"),
    k_r_max: float = typer.Option(300.0, help="k_r is searched in [0, k_r_max]"),
    a: float = typer.Option(1.0, help="weight of H, per rad"),
    b: float = typer.Option(1.0, help="weight of D, per m"),
    c: float = typer.Option(0.5, help="weight of Q, per s"),
    d: float = typer.Option(-1.0, help="weight of P, per m (negative: keeping away is good)"),
    as_json: bool = typer.Option(False, "--json", help="print only the JSON object"),
) -> None:
    from agents.lib.control.tuning import CostWeights, TuningError, default_scenarios, tune_gains

    started = time.perf_counter()
    try:
        weights = CostWeights(a=a, b=b, c=c, d=d)
        result = tune_gains(default_scenarios(), start={"k_c": start_k_c, "k_r": start_k_r},
                            bounds={"k_c": (0.0, k_c_max), "k_r": (0.0, k_r_max)}, weights=weights,
                            samples=samples, max_rounds=rounds, max_evaluations=max_evaluations)
    except (TuningError, ValueError) as exc:
        typer.echo(f"tune_gains: {exc}", err=True)
        raise typer.Exit(2) from exc
    descent = result.descent
    summary = {
        "k_c": descent.best["k_c"], "k_r": descent.best["k_r"], "G": descent.best_cost,
        "start_k_c": descent.start["k_c"], "start_k_r": descent.start["k_r"], "start_G": descent.start_cost,
        "evaluations": descent.evaluations, "rounds": descent.rounds,
        "scenarios": len(result.terms), "failed_runs": sum(t.failed for t in result.terms.values()),
        "elapsed_s": round(time.perf_counter() - started, 3),
    }
    if not as_json:
        _print_tables(result)
    typer.echo(json.dumps(summary))


def _print_tables(result: TuningResult) -> None:
    from rich.console import Console
    from rich.table import Table

    descent = result.descent
    gains = Table(title="elastic band gains (units: robot length / 1000 per iteration)")
    for column in ("", "k_c", "k_r", "G"):
        gains.add_column(column, justify="right")
    gains.add_row("start", f"{descent.start['k_c']:.1f}", f"{descent.start['k_r']:.1f}",
                  f"{descent.start_cost:.3f}")
    gains.add_row("found", f"{descent.best['k_c']:.1f}", f"{descent.best['k_r']:.1f}",
                  f"{descent.best_cost:.3f}")
    terms = Table(title="terms at the gains found")
    for column in ("scenario", "H (rad)", "D (m)", "Q (s)", "P (m)", "failed"):
        terms.add_column(column, justify="right")
    for name, t in result.terms.items():
        terms.add_row(name, f"{t.H:.2f}", f"{t.D:.2f}", f"{t.Q:.1f}", f"{t.P:.2f}", str(t.failed))
    console = Console()
    console.print(gains)
    console.print(terms)


if __name__ == "__main__":
    app()
