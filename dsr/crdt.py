"""State of one replicated element (node or edge) and its join (merge).

Why this shape: each element is an add-wins observed-remove set member plus a map of
last-writer-wins registers, and every field is a join-semilattice (per-replica max, max, or
LWW max), so merging is commutative, associative and idempotent by construction, and a delta is
just a small state.  Per element:

- ``add[replica] = hlc`` of the latest add ("dot") by that replica;
  ``rem[replica] = hlc``: every add of that replica up to this hlc was observed by a remove.
  Present  <=>  some replica's add is newer than what removes observed  (add-wins: an add
  concurrent with a remove was not observed by it, so it survives).
- ``cleared``: hlc of the latest remove; registers written at or before it are hidden, so a
  re-added element does not resurrect attributes of its previous life.  An HLC of a causally
  later write is always larger, so only concurrent writes can land on either side.  Hidden
  registers can never become visible again (``cleared`` only grows), so they are not kept:
  the join drops them (deleted values cost no memory and are never relayed), except the
  removal receipt, which proves who removed the element.
- ``meta``: nodes' (type, name) as one LWW register; ``attrs``: one LWW register per key.
  Registers are ordered by (hlc, replica); equal stamps with different values (only a buggy or
  forged writer does that) are ordered by the value's JSON bytes, keeping the join total.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import orjson

#: (hlc, replica, value)
Register = tuple[int, int, Any]
#: Attribute key of a removal receipt: a remove also writes the register (hlc, remover, True)
#: stamped with its own `cleared` time, so it is hidden at once (registers at or before
#: `cleared` are invisible) yet replicated in states.  Why: a state relays removals without
#: saying who removed; the receipt (LWW, so it names the latest remover) lets write policies
#: check that the remover was allowed to delete the element (dsr/state_review.py).
REMOVAL_RECEIPT = "~removed"
Dots = dict[int, int]
_MISSING = object()


@dataclass(slots=True)
class ElementState:
    add: Dots = field(default_factory=dict)
    rem: Dots = field(default_factory=dict)
    cleared: int = 0
    meta: Register | None = None
    attrs: dict[str, Register] = field(default_factory=dict)
    #: bumped by every change made through this module (merge_attrs, merge_into, prune): the
    #: graph's cache of encoded elements (DSRGraph.state_parts) is valid while it is unchanged
    rev: int = field(default=0, compare=False)

    def present(self) -> bool:
        rem = self.rem
        if not rem:                     # never removed (most elements): any add shows it
            return any(self.add.values())   # (stamps are >= 0; an add stamped 0 shows nothing)
        for replica, hlc in self.add.items():  # noqa: SIM110 - a loop beats any() on this hot path
            if hlc > rem.get(replica, 0):
                return True
        return False

    def visible_attrs(self) -> dict[str, Any]:
        """Copy of the visible attributes (lists copied too: callers may mutate them)."""
        cleared = self.cleared
        return {k: (list(reg[2]) if type(reg[2]) is list else reg[2])
                for k, reg in self.attrs.items() if reg[0] > cleared}

    def visible_value(self, key: str) -> Any:
        reg = self.attrs.get(key)
        if reg is None or reg[0] <= self.cleared:
            return _MISSING
        return list(reg[2]) if type(reg[2]) is list else reg[2]

    def prune(self) -> None:
        """Drop the registers hidden by `cleared` (not the removal receipt)."""
        cleared = self.cleared
        if cleared and self.attrs:
            attrs = self.attrs
            hidden = [k for k, reg in attrs.items() if reg[0] <= cleared and k != REMOVAL_RECEIPT]
            for key in hidden:
                del attrs[key]
            if hidden:
                self.rev += 1

    def copy(self) -> ElementState:
        return ElementState(dict(self.add), dict(self.rem), self.cleared, self.meta,
                            dict(self.attrs))

    def max_hlc(self) -> int:
        """Largest timestamp mentioned anywhere (for clock observation)."""
        best = max(self.cleared, max(self.add.values(), default=0), max(self.rem.values(), default=0))
        if self.meta is not None and self.meta[0] > best:
            best = self.meta[0]
        for reg in self.attrs.values():
            if reg[0] > best:
                best = reg[0]
        return best


def removal_receipt(hlc: int, replica: int) -> dict[str, Register]:
    """The hidden receipt register a remove writes along with `cleared=hlc`."""
    return {REMOVAL_RECEIPT: (hlc, replica, True)}


def register_wins(new: Register, old: Register | None) -> bool:
    """True if `new` must replace `old` in a LWW register."""
    if old is None:
        return True
    if new[0] != old[0]:
        return new[0] > old[0]
    if new[1] != old[1]:
        return new[1] > old[1]
    if new[2] == old[2]:
        return False
    return orjson.dumps(new[2]) > orjson.dumps(old[2])


def _join_dots(dst: Dots, src: Any) -> bool:
    changed = False
    for replica, hlc in src:
        if hlc > dst.get(replica, 0):
            dst[replica] = hlc
            changed = True
    return changed


def merge_into(state: ElementState, *, add: Any = None, rem: Any = None, cleared: int = 0,
               meta: Register | None = None, attrs: dict[str, Register] | None = None
               ) -> tuple[bool, list[str]]:
    """Join a delta into `state` in place.

    `add`/`rem` are iterables of (replica, hlc) pairs.  Returns (state_changed, keys) where
    `keys` lists the attributes whose *visible* value changed (cleared or overwritten).
    """
    changed = False
    keys: list[str] = []
    if add and _join_dots(state.add, add):
        changed = True
    if rem and _join_dots(state.rem, rem):
        changed = True
    if cleared > state.cleared:
        old_cleared = state.cleared
        state.cleared = cleared
        changed = True
        hidden = [key for key, reg in state.attrs.items() if reg[0] <= cleared
                  and key != REMOVAL_RECEIPT]
        for key in hidden:
            if state.attrs.pop(key)[0] > old_cleared:
                keys.append(key)
    if meta is not None and register_wins(meta, state.meta):
        state.meta = meta
        changed = True
    if attrs:
        current = state.attrs
        floor = state.cleared
        for key, reg in attrs.items():
            if reg[0] <= floor and key != REMOVAL_RECEIPT:
                continue            # hidden for ever: not kept
            old = current.get(key)
            if register_wins(reg, old):
                current[key] = reg
                changed = True
                old_visible = old[2] if old is not None and old[0] > floor else _MISSING
                new_visible = reg[2] if reg[0] > floor else _MISSING
                if (type(old_visible) is not type(new_visible) or old_visible != new_visible) \
                        and key not in keys:
                    keys.append(key)
    if changed:
        state.rev += 1
    return changed, keys


def merge_attrs(state: ElementState, attrs: dict[str, Register]) -> tuple[bool, list[str]]:
    """Fast path of merge_into for an attribute-only delta (same result, fewer branches).

    A winning register that is hidden (not newer than `cleared`) can only replace a hidden one,
    so it changes the state but no visible key."""
    current = state.attrs
    floor = state.cleared
    changed = False
    keys: list[str] = []
    for key, reg in attrs.items():
        if reg[0] <= floor and key != REMOVAL_RECEIPT:
            continue                # hidden for ever: not kept
        old = current.get(key)
        if old is None or register_wins(reg, old):
            current[key] = reg
            changed = True
            if reg[0] > floor and (old is None or old[0] <= floor
                                   or type(old[2]) is not type(reg[2]) or old[2] != reg[2]):
                keys.append(key)
    if changed:
        state.rev += 1
    return changed, keys


def join_states(dst: ElementState, src: ElementState) -> tuple[bool, list[str]]:
    """Join a whole element state into another (used for coalescing outgoing deltas)."""
    return merge_into(dst, add=src.add.items(), rem=src.rem.items(), cleared=src.cleared,
                      meta=src.meta, attrs=src.attrs)
