"""Who really wrote what a state reply relays: refuse forged stamps and lying `writers` tables.

Why: a state reply from member S relays the writes of every agent S ever merged, each stamped
with the replica id of its writer, and a `writers` table mapping replica ids to agents.  Nothing
signs them, so S could stamp a register with sim_robot's replica id, or claim in its table that
a fresh replica id belongs to sim_robot, and the write policy would then judge the write as
sim_robot's.  What this replica knows first-hand closes that hole for every writer that is
running:

- a replica id belongs to an agent when a message on that agent's own key (its deltas, digests
  or state reply; the router's ACL gives each agent's key space to that agent's credentials)
  says so, or when the agent's own state reply lists it (its previous incarnations);
- a relayed table entry that gives a replica id to ANOTHER agent that is running, while that
  agent never used or vouched for it (its own state, merged here, lists its replica ids), is
  a lie: its stamps are refused (reason forged_writer); before that agent's own state has been
  merged here, such stamps are only deferred;
- a running writer's deltas reach this replica directly, in order (one publisher, reliable);
  `seen[z]` says up to which stamp this replica holds every write of replica z.  A relayed
  stamp of a running writer z that would change this replica's state is either forged
  (stamp <= seen[z]: z published everything up to there, and not this; reason forged_stamp) or
  not yet arrived from z itself (stamp > seen[z]: dropped here, z's own delta or state brings
  it; counted as `deferred`).  `seen[z]` exists only once z's own state has been merged here
  (dsr/membership.py `advance`): until then every such stamp is deferred.

- this replica knows first-hand what it wrote itself: a relayed stamp of its own replica id
  that would change it is forged whatever its time (forged_stamp), and a table entry giving
  its own agent a replica id it does not know is a lie (forged_writer); the transport then
  publishes a digest at once, so members that deferred the claim fetch its state and refuse
  the claim from then on;
- a relayed removal that hides nothing this replica shows (an old removal on an element added
  again, which another member has already compacted) forges nothing: it is not judged.

What a replica serves in its own state replies is decided elsewhere (DSRGraph.served_writers,
admission `note_state_writers`): only bindings it can prove, never a claim it relayed or deferred,
so a lie told to one member is not repeated as that member's word.

Writes of agents that are not running (a previous incarnation, a tool that has exited) can
only come relayed: they are attributed through the table and judged by the write policy.  The
first state a replica merges when it joins has nothing to be checked against and is trusted
this way (documented limit, docs/dsr_wire_format.md "Trust").
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

from dsr.crdt import REMOVAL_RECEIPT, ElementState, register_wins
from dsr.wire import Decoded

#: (reason code, sentence)
Problem = tuple[str, str]


@dataclass
class Screened:
    message: Decoded
    problems: list[Problem] = field(default_factory=list)
    refused: int = 0
    deferred: int = 0
    #: the state forged a claim about this replica's own agent (a table entry it never made,
    #: or a stamp of its own replica id it never wrote): it should make its own state known
    about_me: bool = False

#: the watermark of this replica's own id: it holds every write it ever stamped
_ALL_OF_IT = 2**64


def _stampers(state: ElementState) -> Iterator[int]:
    yield from state.add
    if state.meta is not None:
        yield state.meta[1]
    for reg in state.attrs.values():
        yield reg[1]


def screen_state(message: Decoded, *, local: Callable[[str, object], ElementState | None],
                 binding: Callable[[int], str | None], live: set[str],
                 seen: dict[int, int], vouched: set[str] | None = None,
                 me: tuple[str, int] | None = None,
                 attributed: Callable[[int], str | None] | None = None) -> Screened:
    """The part of a state reply whose stamps are credible (see the module docstring).

    `vouched`: running agents whose own state (current incarnation) this replica has merged,
    so it knows every replica id they vouch for; a table entry for another of them is a lie.
    For a running agent not in it the entry cannot be judged yet: its stamps are deferred.

    `me`: (this replica's agent, its replica id).  This replica knows first-hand what it
    wrote: a stamp of its own id that would change its state is forged whatever its time
    (forged_stamp), and a table entry giving its agent a replica id it does not know (its own,
    or a previous incarnation listed in the state it joined with) is forged (forged_writer).

    `attributed`: this replica's attribution of replica ids, relayed ones included (a claim
    relayed while its agent was not running): a stamp it gives to a running agent is judged
    like one the table gives to it."""
    vouched = live if vouched is None else vouched
    result = Screened(message)
    my_agent, my_replica = me if me is not None else (None, 0)
    if me is not None:
        seen = {**seen, my_replica: _ALL_OF_IT}
    lying, writers = _judge_table(result, binding, live, vouched, my_agent)

    def agent_of(replica: int) -> str | None:
        agent = binding(replica) or writers.get(str(replica))
        if agent is None and attributed is not None:
            agent = attributed(replica)
        return agent

    suspects = _suspects(message, lying, agent_of, live)
    if not suspects:
        if lying or writers != message.writers:
            result.message = _with(message, message.nodes, message.edges, writers)
        return result
    nodes = [(k, _screen(result, "node", k, s, local("node", k), suspects, lying, seen))
             for k, s in message.nodes]
    edges = [(k, _screen(result, "edge", k, s, local("edge", k), suspects, lying, seen))
             for k, s in message.edges]
    result.message = _with(message, nodes, edges, writers)
    return result


def _judge_table(result: Screened, binding: Callable[[int], str | None], live: set[str],
                 vouched: set[str], my_agent: str | None) -> tuple[dict[int, str], dict[str, str]]:
    """The lying entries of a state's `writers` table (replica -> the agent it names) and the
    table without them; one forged_writer problem for all of them."""
    message = result.message
    sender = message.agent
    lying: dict[int, str] = {}
    writers = dict(message.writers)
    for key, agent in message.writers.items():
        replica = int(key)
        known = binding(replica)
        if known is not None or agent == sender or replica == message.replica:
            continue
        if agent == my_agent:
            # this agent learnt its previous incarnations from the state it joined with (and
            # a relay serves only what it can prove): an id it does not know is not its own
            result.about_me = True
        elif not (agent in vouched and agent in live):
            continue
        lying[replica] = agent
        del writers[key]
    if lying:                               # one refusal per state, however many entries
        replica, agent = next(iter(lying.items()))
        more = f" (and {len(lying) - 1} more such entries)" if len(lying) > 1 else ""
        result.problems.append((
            "forged_writer", f"state of {sender!r} says replica {replica} is {agent!r}, "
            f"but {agent!r} is running and never used or vouched for that replica{more}"))
    return lying, writers


def _suspects(message: Decoded, lying: dict[int, str],
              agent_of: Callable[[int], str | None], live: set[str]) -> dict[int, str]:
    """Replicas whose relayed stamps must be checked: running agents other than the sender,
    and the replica ids the table lied about."""
    sender = message.agent
    suspects: dict[int, str] = {}
    for entries in (message.nodes, message.edges):
        for _, state in entries:
            for replica in _stampers(state):
                if replica in suspects or replica == message.replica:
                    continue
                agent = lying.get(replica) or agent_of(replica)
                if agent is not None and agent != sender and (agent in live or replica in lying):
                    suspects[replica] = agent
    return suspects


def removal_changes_view(state: ElementState, held: ElementState | None) -> bool:
    """Would merging the removal information of `state` (its `rem` dots and `cleared`) hide
    anything `held` shows?  A removal that hides nothing (an old removal of an element that
    was added again since, which another member has already forgotten: compaction is not
    simultaneous) is covered by what this replica holds: relaying it proves nothing and
    forges nothing, so it is never called forged (docs/dsr_wire_format.md, "Tombstones")."""
    if held is None:
        return False
    rem = state.rem
    for replica, hlc in held.add.items():
        if hlc > held.rem.get(replica, 0) and hlc <= rem.get(replica, 0):
            return True
    cleared = state.cleared
    if cleared > held.cleared:
        floor = held.cleared
        for key, reg in held.attrs.items():
            if key != REMOVAL_RECEIPT and floor < reg[0] <= cleared:
                return True
    return False


def _with(message: Decoded, nodes: list[tuple[int, ElementState]],
          edges: list[tuple[tuple[int, int, str], ElementState]], writers: dict[str, str]
          ) -> Decoded:
    return Decoded(message.kind, message.graph, message.agent, message.replica, writers, nodes,
                   edges, message.top_hlc, message.clock, message.seen)


def _screen(result: Screened, element: str, key: object, state: ElementState,
            held: ElementState | None, suspects: dict[int, str], lying: dict[int, str],
            seen: dict[int, int]) -> ElementState:
    """`state` minus the suspect stamps that would change `held` (this replica's element)."""
    if not any(r in suspects for r in _stampers(state)):
        return state
    if held is None and not state.present():
        return state     # an unknown tombstone changes no view; the policy judges its receipt
    bad: set[tuple[str, object]] = set()

    def judge(what: tuple[str, object], replica: int, hlc: int, new: bool) -> None:
        if replica not in suspects or not new:
            return
        agent = suspects[replica]
        bad.add(what)
        if replica in lying:
            result.refused += 1
            return
        watermark = seen.get(replica, 0)
        if hlc <= watermark:
            result.refused += 1
            result.about_me = result.about_me or watermark == _ALL_OF_IT
            if len(result.problems) < 5:
                result.problems.append((
                    "forged_stamp", f"state of {result.message.agent!r} carries a write "
                    f"stamped by {agent!r} (replica {replica}, hlc {hlc}) on {element} {key} "
                    f"that {agent!r} never published"))
        else:
            result.deferred += 1

    held_add = held.add if held is not None else {}
    held_rem = held.rem if held is not None else {}
    floor = held.cleared if held is not None else 0
    for replica, hlc in state.add.items():
        judge(("add", replica), replica, hlc,
              hlc > held_add.get(replica, 0) and hlc > held_rem.get(replica, 0))
    if state.meta is not None:
        judge(("meta", None), state.meta[1], state.meta[0],
              register_wins(state.meta, held.meta if held is not None else None))
    for attr, reg in state.attrs.items():
        if attr == REMOVAL_RECEIPT:
            judge(("removal", None), reg[1], reg[0],
                  reg[0] > floor and removal_changes_view(state, held))
        else:
            judge(("attr", attr), reg[1], reg[0], reg[0] > floor and register_wins(
                reg, held.attrs.get(attr) if held is not None else None))
    return _without(state, bad) if bad else state


def _without(state: ElementState, bad: set[tuple[str, object]]) -> ElementState:
    """`state` minus the pieces judged forged or deferred: adds, type/name, registers, or the
    removal (its dots, its clearing and its receipt go together)."""
    kept = ElementState(add={r: h for r, h in state.add.items() if ("add", r) not in bad},
                        meta=None if ("meta", None) in bad else state.meta,
                        attrs={k: v for k, v in state.attrs.items() if ("attr", k) not in bad})
    if ("removal", None) in bad:
        kept.attrs.pop(REMOVAL_RECEIPT, None)
    else:
        kept.rem, kept.cleared = dict(state.rem), state.cleared
    return kept
