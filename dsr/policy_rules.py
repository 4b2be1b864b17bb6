"""The declarative write policy: a table of grants (chronav ships its own: agents/world/write_policy.yaml).

Why a table of grants (default deny): the question an operator asks is "who may move the robot?",
and the answer must be one place to read, not code.  Each rule grants some writers (agent names
or fnmatch patterns such as ``agenda_tool-*``) some operations on some node or edge types:

```yaml
format: chronav-write-policy/1
rules:
  - writers: [sim_robot]
    nodes: [robot]
    ops: [create, delete]                   # create includes the initial attribute values
    attrs: [pose_stamp, v, vy, omega, laser_ranges]
  - writers: [social_navigation]
    nodes: [robot]
    attrs: [nav_active, "cmd_*", "path_*", planned_s]
  - writers: [human_observer]
    edges: [RT]
    from: [world]                           # edge rules may restrict the end node types
    to: [person]
    ops: [create, delete]
    attrs: [x, y, theta]
    init_attrs: []                          # create brings only the named attributes
```

A write is allowed when some rule matches its writer, element type (and end types), and grants
its operation (`create`, `delete`) or its attribute (`attrs` patterns minus `except_attrs`).
Values given at creation come with `create`, except the keys of `except_attrs`, and a key of
`init_values` only with one of the values it lists (a staff tool creates an `agenda_request`
`pending`; only the agenda may answer it).  A rule that lists `init_attrs` (even empty) lets
`create` bring only the values of `attrs` and `init_attrs`: chronav's own table, generated from
its vocabulary (agents/world/write_policy.py), names every attribute that way.
Deleting a node also deletes its edges: such edge deletes are allowed to whoever may delete the
node.  Types this replica has not seen yet (a delta overtaking the node's creation) match any
pattern: the write lands on an element nobody can see until its creator's write arrives.
Deltas and states from an agent holding no grant at all are refused whole; other states keep
the part their writers were allowed to write (dsr/state_review.py).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from fnmatch import fnmatchcase
from typing import TYPE_CHECKING, Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, StringConstraints, model_validator

from dsr.state_review import review_state
from dsr.writes import Write, delta_writes, explain

if TYPE_CHECKING:
    from dsr.wire import Decoded
    from dsr.writes import GraphLookup

FORMAT = "chronav-write-policy/1"
_CACHE_LIMIT = 65536

Pattern = Annotated[str, StringConstraints(min_length=1, max_length=128, pattern=r"^\S+$")]


class Rule(BaseModel):
    """One grant.  Exactly one of `nodes` / `edges`; at least one of `ops` / `attrs`."""

    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True)
    writers: list[Pattern] = Field(min_length=1)
    nodes: list[Pattern] = []
    edges: list[Pattern] = []
    from_: list[Pattern] = Field(default=["*"], alias="from", min_length=1)
    to: list[Pattern] = Field(default=["*"], min_length=1)
    ops: list[Literal["create", "delete"]] = []
    attrs: list[Pattern] = []
    except_attrs: list[Pattern] = []
    #: with `create`: the keys (besides `attrs`) whose values may be given at creation only.  When
    #: absent, `create` brings any initial value (hand-written tables); when present (even `[]`),
    #: only the named ones (chronav's table, generated from its vocabulary, always names them)
    init_attrs: list[Pattern] | None = None
    #: attribute -> the only values it may be given at creation under this rule's `create`
    #: (e.g. a request must be created `pending`: only its answerer sets another state)
    init_values: dict[Annotated[str, StringConstraints(min_length=1, max_length=128)],
                      list[str | bool | int | float]] = {}
    #: why the grant exists (documentation only)
    why: str = ""

    @model_validator(mode="after")
    def _shape(self) -> Rule:
        if bool(self.nodes) == bool(self.edges):
            raise ValueError("a rule names either `nodes` or `edges` (exactly one)")
        if self.nodes and ({"from_", "to"} & self.model_fields_set):
            raise ValueError("`from`/`to` restrict edge rules only")
        if not self.ops and not self.attrs:
            raise ValueError("a rule grants `ops`, `attrs` or both")
        if self.except_attrs and not self.attrs:
            raise ValueError("`except_attrs` needs `attrs`")
        if self.init_attrs is not None and "create" not in self.ops:
            raise ValueError("`init_attrs` names values given at creation: needs `ops: [create]`")
        if self.init_values and "create" not in self.ops:
            raise ValueError("`init_values` restricts values given at creation: needs "
                             "`ops: [create]`")
        return self

    def permits(self, write: Write) -> bool:
        if write.element == "node":
            if not _match(write.type, self.nodes):
                return False
        elif not (_match(write.type, self.edges) and _match(write.src, self.from_)
                  and _match(write.dst, self.to)):
            return False
        if write.op in ("attr", "init"):
            key = write.attr or ""
            if any(fnmatchcase(key, p) for p in self.except_attrs):
                return False
            if write.op == "init" and key in self.init_values:
                return write.value in self.init_values[key]
            if _match(key, self.attrs):
                return True
            # a value given at creation comes with the create grant (only the named ones when
            # the rule names them in `init_attrs`)
            return write.op == "init" and "create" in self.ops and (
                self.init_attrs is None or _match(key, self.init_attrs))
        return write.op in self.ops


class PolicyDocument(BaseModel):
    model_config = ConfigDict(extra="forbid")
    format: Literal["chronav-write-policy/1"]
    rules: list[Rule]


def _match(value: str | None, patterns: Iterable[str]) -> bool:
    """fnmatch against any pattern; an unknown (None) type matches any non-empty list."""
    patterns = list(patterns)
    if value is None:
        return bool(patterns)
    return any(fnmatchcase(value, p) for p in patterns)


class RulePolicy:
    """Evaluates writes against the rules; decisions are cached (the vocabulary is small)."""

    def __init__(self, rules: Sequence[Rule], source: str = "<rules>") -> None:
        self.rules = tuple(rules)
        self.source = source
        self._by_writer: dict[str, tuple[Rule, ...]] = {}
        self._decisions: dict[Write, bool] = {}
        #: keys some rule restricts at creation: only their initial values enter the questions
        self.valued: frozenset[str] = frozenset(k for r in self.rules for k in r.init_values)

    def rules_for(self, agent: str) -> tuple[Rule, ...]:
        found = self._by_writer.get(agent)
        if found is None:
            found = tuple(r for r in self.rules if any(fnmatchcase(agent, p) for p in r.writers))
            if len(self._by_writer) >= _CACHE_LIMIT:
                self._by_writer.clear()
            self._by_writer[agent] = found
        return found

    def has_rights(self, agent: str) -> bool:
        return bool(self.rules_for(agent))

    def allowed(self, write: Write) -> bool:
        decision = self._decisions.get(write)
        if decision is None:
            decision = self._decide(write)
            if len(self._decisions) >= _CACHE_LIMIT:
                self._decisions.clear()
            self._decisions[write] = decision
        return decision

    def _decide(self, write: Write) -> bool:
        if write.writer is None:
            return False
        if any(rule.permits(write) for rule in self.rules_for(write.writer)):
            return True
        if write.op == "delete" and write.element == "edge" and write.cascade is not None:
            return self.allowed(Write(write.writer, "node", write.cascade, "delete"))
        return False

    def _no_grant(self, agent: str) -> str | None:
        if self.has_rights(agent):
            return None
        return f"agent {agent!r} holds no grant in {self.source}"

    def check(self, message: Decoded, graph: GraphLookup) -> str | None:
        problem = self._no_grant(message.agent)
        if problem is not None:
            return problem
        for write in delta_writes(message, graph, self.valued):
            if not self.allowed(write):
                return f"{explain(write)} ({self.source})"
        return None

    def refusal(self, write: Write) -> str | None:
        """For local writes: the refusal naming the grant the writer lacks, or None."""
        if self.allowed(write):
            return None
        return (f"{explain(write)}: no rule of {self.source} grants it (the other replicas "
                "would drop this write)")

    def review_state(self, message: Decoded, graph: GraphLookup
                     ) -> tuple[Decoded | None, str | None]:
        problem = self._no_grant(message.agent)
        if problem is not None:
            return None, f"{problem}: its state is not trusted"
        kept, dropped = review_state(message, graph, self.allowed, self.valued)
        return kept, None if dropped is None else f"{dropped} ({self.source})"
