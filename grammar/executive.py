"""The primitive plan AGM's executive runs for a target: hierarchical steps replaced, in turn, by
the primitive steps that realise them, re-planning after each step as the executive does.

Why not ``Plan.flat_steps()``: a plan's later hierarchical step is expanded from the abstract
world its plan predicts (the hierarchical rule's right-hand side), not from the world the first
step's primitive steps actually leave (an egg fried by ``*fryH`` is on the fire, not where it was
before), so splicing the expansions together can give steps that do not apply. AGM's executive
runs the first action of the plan (the first primitive step of a hierarchical step's expansion,
recursively), then plans again from the world that action made. This module does the same on the
planner's own states, so the lines it returns are the actions AGM's executive would run, one per
line, comparable with a plan AGM recorded (issue 43: AGM's 9 primitive steps for the egg grammar's
problem p1 where chronav's plan has 2 hierarchical steps).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import networkx as nx

from grammar.model import Grammar, Target
from grammar.planner import (DEFAULT_MAX_EXPANSIONS, GROWTH_STEPS, NoPlan, Plan, PlanResult, PlanStep, Planner,
                             plan_growing)
from grammar.world import State, World

MAX_PRIMITIVE_STEPS = 500
"""Primitive steps one run may take: a grammar whose hierarchical rules promise what their
expansions never deliver would otherwise make the executive re-plan for ever."""

Replanner = Callable[[State, dict[int, str]], PlanResult]
"""Plans the target from a state (with the AGM ids of the symbols it created so far)."""


@dataclass(frozen=True)
class PrimitivePlan:
    """The primitive steps the executive runs, in order; ``plans`` counts the plans it made."""

    steps: tuple[PlanStep, ...]
    cost: float
    plans: int
    expanded: int
    final_state: State | None = field(default=None, compare=False, repr=False)
    found: bool = field(default=True, init=False)

    def agm_lines(self) -> list[str]:
        """One AGM plan-file line per primitive step (``rule@{'var': 'id', ...}``)."""
        return [step.agm_line() for step in self.steps]


def _first_primitive(plan: Plan) -> tuple[PlanStep, Plan]:
    """The first action the executive runs for ``plan`` and the (sub-)plan it belongs to."""
    step = plan.steps[0]
    while step.hierarchical:
        if step.expansion is None or not step.expansion.steps:
            break  # an expansion with no step: the rule's right-hand side already holds
        plan = step.expansion
        step = plan.steps[0]
    return step, plan


def run_executive(replan: Replanner, start: State, target: Target, goal: Callable[[State], bool], *,
                  max_steps: int = MAX_PRIMITIVE_STEPS) -> PrimitivePlan | NoPlan:
    """Plan, run the first primitive action, plan again from the world it made, until ``goal``.

    ``replan(state, created_ids)`` must return the planner's plan (with hierarchical steps
    expanded) from ``state``. A first step that is hierarchical and whose expansion is empty is
    taken as done by its rule (its right-hand side already holds), as AGM does."""
    state = start
    ids: dict[int, str] = {}
    steps: list[PlanStep] = []
    plans = expanded = 0
    cost = 0.0
    while not goal(state):
        if len(steps) >= max_steps:
            return NoPlan(f"the executive ran {max_steps} primitive steps without reaching the target "
                          f"(the limit, docs/limits.md): the hierarchical rules' expansions do not lead to it",
                          expanded)
        result = replan(state, ids)
        plans += 1
        expanded += result.expanded
        if not isinstance(result, Plan):
            done = f" after {len(steps)} primitive step(s)" if steps else ""
            return NoPlan(f"no plan{done}: {result.reason}", expanded, result.generated, result.diagnosis)
        if not result.steps:
            break
        step, owner = _first_primitive(result)
        after = step.state_after
        if after is None:  # pragma: no cover - the planner always records it
            raise AssertionError("a plan step without the state after it")
        steps.append(step)
        cost += step.cost
        ids = {n: i for n, i in owner.created_ids.items() if after.exists(n)}
        state = after
    return PrimitivePlan(tuple(steps), cost, plans, expanded, state)


def primitive_plan(grammar: Grammar, world: nx.MultiDiGraph | World, target: Target, *,
                   max_expansions: int = DEFAULT_MAX_EXPANSIONS,
                   steps: tuple[int | None, ...] = GROWTH_STEPS) -> PrimitivePlan | NoPlan:
    """``run_executive`` with the planner ``chronav plan --world/--target`` uses (``plan_growing``)."""
    world = world if isinstance(world, World) else World(world)
    judge = Planner(grammar, world)
    pattern = judge.matcher.compile(target.pattern)

    def replan(state: State, ids: dict[int, str]) -> PlanResult:
        return plan_growing(grammar, world, target, max_expansions=max_expansions, steps=steps,
                            start=state, created_ids=ids)[0]

    return run_executive(replan, world.initial_state(), target,
                         lambda state: judge.target_match(target, pattern, state) is not None)
