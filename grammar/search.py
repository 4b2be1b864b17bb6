"""A* over any task that names its start, its goal test and its successors (the search alone).

Why a module of its own: the symbolic planner composes three separate things, the search, the
pruning of irrelevant rules (relevance.py) and the explanation of a failed search (diagnosis.py);
with A* written inline beside the other two, none of them could be tested or read alone. Here the
search knows nothing of grammars: ``astar(task, heuristic)`` runs on any ``SearchTask`` (a toy
task in tests/unit/test_grammar_search.py, as pyperplan tests its searches, and the grammar
planner's task in planner.py).

Guarantees: with an admissible heuristic the first goal popped is a cheapest one; ties break on
(f, h, insertion order), so the same task always gives the same result. Two bounds keep a search
that cannot succeed from running away: ``max_expansions`` (states expanded) and ``max_size`` (the
total size, by ``task.size``, of every state the search keeps). The second matters when each step
makes states larger (a rule that creates a node every time it applies): then the kept states grow
with the square of the expansions, and the expansion bound alone let a one-rule grammar take
3.8 GB (docs/limits.md).
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable, Hashable, Iterable
from dataclasses import dataclass, field
from typing import Generic, Literal, Protocol, TypeVar

S = TypeVar("S", bound=Hashable)
A = TypeVar("A")
A_co = TypeVar("A_co", covariant=True)


class SearchTask(Protocol[S, A_co]):
    """What a search needs to know of a problem. States must be hashable (they key the search)."""

    def initial(self) -> S:
        """The state the search starts from."""
        ...

    def goal(self, state: S) -> object | None:
        """A witness (anything but None) when ``state`` satisfies the goal, else None."""
        ...

    def successors(self, state: S) -> Iterable[tuple[A_co, S, float]]:
        """(action, next state, cost >= 0) for every action applicable in ``state``, in a fixed order."""
        ...

    def size(self, state: S) -> int:
        """How much memory keeping ``state`` costs, in any unit the bound ``max_size`` uses."""
        ...


@dataclass(frozen=True)
class Step(Generic[S, A]):
    """One action of a found path: the state before it, the action, the state after it."""

    before: S
    action: A
    after: S


@dataclass(frozen=True)
class SearchResult(Generic[S, A]):
    """How a search ended. ``outcome`` is ``"found"`` (``path``, ``cost``, ``goal`` and ``witness``
    set), ``"exhausted"`` (every reachable state expanded), ``"expansion_limit"`` or
    ``"size_limit"``. ``closed`` lists the first ``record`` expanded states in expansion order
    (what a diagnosis reads); on ``"size_limit"``, ``kept`` pairs the action that produced each
    kept state with that state's size (what filled the bound)."""

    outcome: Literal["found", "exhausted", "expansion_limit", "size_limit"]
    expanded: int
    generated: int
    size: int
    path: tuple[Step[S, A], ...] = ()
    cost: float = math.inf
    goal: S | None = None
    witness: object | None = None
    closed: tuple[S, ...] = field(default=(), compare=False, repr=False)
    kept: tuple[tuple[A, int], ...] = field(default=(), compare=False, repr=False)

    @property
    def found(self) -> bool:
        return self.outcome == "found"


def zero(state: object) -> float:
    """The heuristic of uniform-cost search (always admissible)."""
    return 0.0


def astar(task: SearchTask[S, A], heuristic: Callable[[S], float] = zero, *,
          max_expansions: int = 20_000, max_size: int | None = None, record: int = 0,
          key: Callable[[S], Hashable] | None = None) -> SearchResult[S, A]:
    """A* from ``task.initial()`` to the first state ``task.goal`` accepts.

    A state whose heuristic is ``math.inf`` is never queued (a dead end). ``max_size`` bounds the
    sum of ``task.size`` over the states kept (queued, closed or on a path): reaching it ends the
    search with ``"size_limit"`` and ``kept`` (the action that produced each kept state, and its
    size). ``record`` keeps that many expanded states in ``closed``. ``key`` maps a state to what
    identifies it for the search (default: the state itself); states with equal keys are one
    state, represented by the first reached at its best cost. It must only equate states that
    have the same goal test, heuristic and successors up to the same renaming (the planner's
    canonical key, grammar/canonical.py).
    """
    ident: Callable[[S], Hashable] = key if key is not None else _identity
    start = task.initial()
    h0 = heuristic(start)
    size = task.size(start)
    if h0 == math.inf:
        return SearchResult("exhausted", 0, 0, size)
    counter = 0
    k0 = ident(start)
    queue: list[tuple[float, float, int, S, Hashable]] = [(h0, h0, counter, start, k0)]
    best_g: dict[Hashable, float] = {k0: 0.0}
    rep: dict[Hashable, S] = {k0: start}  # the state that stands for its key (the best reached)
    parent: dict[Hashable, tuple[S, A, int]] = {}
    closed: set[Hashable] = set()
    order: list[S] = []
    expanded = generated = 0
    while queue:
        _, _, _, state, k = heapq.heappop(queue)
        if k in closed or rep[k] is not state:
            continue
        g = best_g[k]
        witness = task.goal(state)
        if witness is not None:
            return SearchResult("found", expanded, generated, size, _path(state, parent, ident), g, state, witness,
                                tuple(order))
        if expanded >= max_expansions:
            return SearchResult("expansion_limit", expanded, generated, size, closed=tuple(order))
        closed.add(k)
        if len(order) < record:
            order.append(state)
        expanded += 1
        for action, nxt, cost in task.successors(state):
            generated += 1
            k2 = ident(nxt)
            if k2 in closed:
                continue
            g2 = g + cost
            old = best_g.get(k2)
            if old is not None and g2 >= old:
                continue
            h2 = heuristic(nxt)
            if h2 == math.inf:
                continue
            grown = 0
            if old is None:  # a state new to the search: it is kept from now on
                grown = task.size(nxt)
                size += grown
                if max_size is not None and size > max_size:
                    kept = [(a, n) for _, a, n in parent.values()] + [(action, grown)]
                    return SearchResult("size_limit", expanded, generated, size, closed=tuple(order),
                                        kept=tuple(kept))
            else:
                grown = parent[k2][2] if k2 in parent else 0
            best_g[k2] = g2
            rep[k2] = nxt
            parent[k2] = (state, action, grown)
            counter += 1
            heapq.heappush(queue, (g2 + h2, h2, counter, nxt, k2))
    return SearchResult("exhausted", expanded, generated, size, closed=tuple(order))


def _identity(state: S) -> Hashable:
    return state


def _path(state: S, parent: dict[Hashable, tuple[S, A, int]], ident: Callable[[S], Hashable]
          ) -> tuple[Step[S, A], ...]:
    steps: list[Step[S, A]] = []
    k = ident(state)
    while k in parent:
        before, action, _ = parent[k]
        steps.append(Step(before, action, state))
        state = before
        k = ident(state)
    steps.reverse()
    return tuple(steps)
