"""The order in which RoboComp's AGM creates a rule's new symbols, so plan files get AGM's ids.

Why this exists: when one rule application creates several symbols, AGM's generated planner code
(``generateAGGLPlannerCode.py``, ``normalRuleImplementation``) numbers them one after the other
with ``getNewIdForSymbol`` (the largest symbol id in the current graph + 1), in the order of
``AGMGraph.getNodeChanges`` (``AGGL.py``)::

    R = dict(other.nodes, **parametersDict)      # the right-hand side's nodes (+ the parameters)
    for name in R.keys():
        if not name in L.keys(): toCreate.append(R[name])

That is the iteration order of a Python 2.7 ``dict`` keyed by the node names: neither the file's
order nor alphabetical, but the layout of CPython 2.7's hash table. A later step of a plan names
the created symbols by the ids AGM gave them, so a plan file whose ids follow another order is
refused by AGM's ``AGGLPlanChecker``. This module reproduces that order exactly:

- the string hash of CPython 2.7 on 64-bit Linux without hash randomisation (``-R`` is off by
  default in Python 2): ``x = s[0] << 7; x = (1000003 * x) ^ c for each byte; x ^= len(s)``;
- the open-addressing table (8 slots to start, probing ``i = 5i + perturb + 1``, ``perturb >>= 5``,
  resized to the smallest power of two above 4x the entries when two thirds full; ``dict(d)``
  pre-sized to twice the entries);
- the history of the node dict: built by the parser in file order (``parseGraphFromAST``), then
  copied by ``dict(other.nodes, **parametersDict)``. AGM's current generator (``generate(agm,
  skipPassiveRules)``) works on the parsed grammar itself: there is no ``copy.deepcopy`` in between
  (a deep copy re-inserts the keys in iteration order, which can swap two of them: chronav modelled
  one until issue 43, and numbered ``rb`` before ``hs`` where AGM numbers ``hs`` first).

Checked against the orders found in planner modules AGM generated (tests/unit/test_grammar_agm_ids.py):
``findObjectVisually`` with right-hand sides ``r cl o re t rb po se`` (created cl, o, re, t, rb, po,
se) and ``r re se cl po o`` (re, se, cl, po, o); the current generator's module for AGM's
AGGLPlanner/example_HRI/clean_table_easy, whose ``tellHumanAboutTable`` side ``c ch oh hr h m mh o p
sr sh rb hs ph r`` (an earlier version of that grammar) is created ch, oh, hr, mh, sh, rb, hs, ph;
and AGM's own plan for that grammar's current version (side ``... sh hs rb sr ph r``), which numbers
hs before rb. Older generators (before rule parameters) iterated ``other.nodes`` itself: the same
order for most sides, not for every one.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

_MASK64 = (1 << 64) - 1
_MIN_SIZE = 8
_PERTURB_SHIFT = 5


def py2_str_hash(text: str) -> int:
    """CPython 2.7's ``hash(str)`` on a 64-bit platform (no randomisation), as a signed C long.
    AGGL names are ASCII (``[A-Za-z0-9_.]``); other characters are hashed by their UTF-8 bytes,
    as Python 2 would hash the byte string."""
    data = text.encode("utf-8")
    if not data:
        return 0
    x = (data[0] << 7) & _MASK64
    for byte in data:
        x = ((1000003 * x) & _MASK64) ^ byte
    x ^= len(data)
    if x >= 1 << 63:
        x -= 1 << 64
    return -2 if x == -1 else x


class _Py2Dict:
    """The slot layout of a CPython 2.7 dict that is only ever inserted into (no deletions)."""

    def __init__(self) -> None:
        self.table: list[tuple[str, int] | None] = [None] * _MIN_SIZE
        self.used = 0

    def _slot(self, key: str, hashed: int) -> int:
        mask = len(self.table) - 1
        i = hashed & mask
        perturb = hashed & _MASK64
        while True:
            entry = self.table[i]
            if entry is None or entry[0] == key:
                return i
            i = ((i << 2) + i + perturb + 1) & mask
            perturb >>= _PERTURB_SHIFT

    def _put(self, key: str, hashed: int) -> bool:
        """``insertdict``: True when the key is new."""
        i = self._slot(key, hashed)
        if self.table[i] is not None:
            return False
        self.table[i] = (key, hashed)
        self.used += 1
        return True

    def _resize(self, minused: int) -> None:
        size = _MIN_SIZE
        while size <= minused:
            size <<= 1
        old = [entry for entry in self.table if entry is not None]
        self.table = [None] * size
        self.used = 0
        for key, hashed in old:
            self._put(key, hashed)

    def setitem(self, key: str) -> None:
        """``d[key] = value`` (``PyDict_SetItem``: resize after a new key fills two thirds)."""
        if self._put(key, py2_str_hash(key)) and self.used * 3 >= len(self.table) * 2:
            self._resize(4 * self.used)

    def merge(self, other: _Py2Dict) -> None:
        """``dict.update(other)`` / ``dict(other)`` (``PyDict_Merge``: one resize up front)."""
        if other.used == 0:
            return
        if (self.used + other.used) * 3 >= len(self.table) * 2:
            self._resize((self.used + other.used) * 2)
        for entry in other.table:
            if entry is not None:
                self._put(*entry)

    def keys(self) -> list[str]:
        return [entry[0] for entry in self.table if entry is not None]


def _built(keys: Iterable[str]) -> _Py2Dict:
    d = _Py2Dict()
    for key in keys:
        d.setitem(key)
    return d


def py2_dict_order(keys: Sequence[str], extra: Sequence[str] = ()) -> list[str]:
    """Iteration order of AGM's ``dict(nodes, **parameters)`` for a graph whose nodes were
    declared in the order ``keys`` (and a rule whose parameters are ``extra``)."""
    parsed = _built(keys)
    result = _Py2Dict()
    result.merge(parsed)
    if extra:
        result.merge(_built(extra))
    return result.keys()


def agm_creation_order(rhs_names: Sequence[str], lhs_names: Iterable[str],
                       parameters: Sequence[str] = ()) -> tuple[str, ...]:
    """The names of the nodes a rule creates (in its RHS, not in its LHS nor its parameters),
    in the order AGM's planner creates them and hence numbers them."""
    old = set(lhs_names) | set(parameters)
    return tuple(name for name in py2_dict_order(rhs_names, parameters) if name not in old)
