"""Grouping people into interacting groups (seed Eqs. 5-8).

Two people are neighbours when they are at most Omega_d apart and each faces the other within
Omega_theta, or when the DSR says they interact (``Person.interacting_with``). Groups are the
connected components of that relation. Within a group the density is the sum of the members'
Gaussians (Eq. 5), so the space between two people talking to each other fills up and the robot
does not cut through the conversation.

Interpretation of Omega_theta. The seed's "difference of angles between two people" read
literally (|theta_i - theta_j|) would make two people facing each other (difference pi) the least
related pair; we read it as the angle between a person's heading and the bearing to the other,
required for both (F-formation: their transactional segments overlap). Defaults (ours; the seed
defers the numbers to its ref. 37): Omega_d = 2.0 m, Omega_theta = pi/2 (side by side or facing).

Between groups the densities are combined by ``max`` by default: two strangers standing back to
back are two groups, and summing their Gaussians would close the gap between them as if they were
talking. ``composition="sum"`` gives Eq. 5 over everybody (the seed's literal global density).

Eqs. 6-7 per group: delta = g_i(h_j) for neighbours i, j (we take the smallest over the group's
neighbour pairs, both directions) and phi = 1 + k delta with k the smallest number of neighbours of
a member; J = {G_d >= phi} (Eq. 8) is the group's core, reported by zones.py.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field

from agents.lib.socialmap.personal_space import PersonalSpace, asymmetric_gaussian
from agents.lib.socialmap.types import Person
from scenes.geometry import wrap_angle


class GroupParams(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    omega_d_m: float = Field(2.0, gt=0, description="largest distance between neighbours (m)")
    omega_theta_rad: float = Field(math.pi / 2, ge=0, le=math.pi,
                                   description="largest angle between a heading and the bearing to the other")
    composition: Literal["max", "sum"] = Field("max", description="how different groups' densities combine")


@dataclass(frozen=True, slots=True)
class Group:
    """A connected set of neighbours (a lone person is a group of one, with k = 0 and phi = 1)."""

    members: tuple[int, ...]       # indices into the people sequence
    names: tuple[str, ...]
    k: int                         # smallest number of neighbours of a member
    delta: float                   # Eq. 6, smallest over the group's neighbour pairs
    phi: float                     # Eq. 7


def are_neighbours(a: Person, b: Person, params: GroupParams) -> bool:
    """The Omega rule (or an explicit interaction between the two)."""
    if b.name in a.interacting_with or a.name in b.interacting_with:
        return True
    dx, dy = b.x - a.x, b.y - a.y
    if math.hypot(dx, dy) > params.omega_d_m:
        return False
    bearing = math.atan2(dy, dx)
    return (abs(wrap_angle(bearing - a.theta)) <= params.omega_theta_rad
            and abs(wrap_angle(bearing + math.pi - b.theta)) <= params.omega_theta_rad)


def density_contribution(person: Person, space: PersonalSpace, other: Person) -> float:
    """Eq. 6: delta = g_i(h_j), person i's Gaussian evaluated at the other's position."""
    return float(asymmetric_gaussian(space, person.x, person.y, person.theta, other.x, other.y))


def group_threshold(k: int, delta: float) -> float:
    """Eq. 7: phi = 1 + k delta, the density a member with k neighbours at least reaches."""
    return 1.0 + k * delta


def group_people(people: Sequence[Person], spaces: Sequence[PersonalSpace], params: GroupParams) -> list[Group]:
    """Connected components of the neighbour relation, with each group's k, delta and phi."""
    n = len(people)
    if n == 0:
        return []
    pairs = [(i, j) for i in range(n) for j in range(i + 1, n) if are_neighbours(people[i], people[j], params)]
    if params.composition == "sum":
        labels = np.zeros(n, dtype=np.int64)
        count = 1
    elif not pairs:  # nobody near anybody: each person is a group of one (scipy labels them so too)
        labels = np.arange(n, dtype=np.int64)
        count = n
    else:
        # scipy.sparse loads here, not at import (~40 ms a fresh `chronav path` need not pay)
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        rows = [i for i, _ in pairs]
        cols = [j for _, j in pairs]
        graph = coo_matrix((np.ones(len(pairs)), (rows, cols)), shape=(n, n))
        count, labels = connected_components(graph, directed=False)
    degree = np.zeros(n, dtype=np.int64)
    for i, j in pairs:
        degree[i] += 1
        degree[j] += 1
    groups: list[Group] = []
    for label in range(count):
        members = tuple(int(i) for i in np.flatnonzero(labels == label))
        member_set = set(members)
        deltas = [min(density_contribution(people[i], spaces[i], people[j]),
                      density_contribution(people[j], spaces[j], people[i]))
                  for i, j in pairs if i in member_set and j in member_set]
        k = int(min(degree[i] for i in members)) if len(members) > 1 else 0
        delta = float(min(deltas)) if deltas else 0.0
        groups.append(Group(members=members, names=tuple(people[i].name for i in members),
                            k=k, delta=delta, phi=group_threshold(k, delta)))
    return groups


def group_density(people: Sequence[Person], spaces: Sequence[PersonalSpace], members: Sequence[int],
                  xs: ArrayLike, ys: ArrayLike) -> NDArray[np.float64]:
    """Eq. 5 restricted to one group: the sum of its members' Gaussians at (xs, ys)."""
    total: NDArray[np.float64] | None = None
    for i in members:
        p = people[i]
        value = asymmetric_gaussian(spaces[i], p.x, p.y, p.theta, xs, ys)
        total = value if total is None else total + value
    if total is None:
        return np.zeros(np.broadcast_shapes(np.shape(xs), np.shape(ys)))
    return total


def social_density(people: Sequence[Person], spaces: Sequence[PersonalSpace], groups: Sequence[Group],
                   xs: ArrayLike, ys: ArrayLike) -> NDArray[np.float64]:
    """The density the zones are cut from: max over groups of each group's sum (see module doc).

    With ``composition="sum"`` there is one group with everybody, i.e. Eq. 5 exactly."""
    result: NDArray[np.float64] | None = None
    for group in groups:
        value = group_density(people, spaces, group.members, xs, ys)
        result = value if result is None else np.maximum(result, value)
    if result is None:
        return np.zeros(np.broadcast_shapes(np.shape(xs), np.shape(ys)))
    return result
