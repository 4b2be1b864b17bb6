"""What survived a chaos run: do the replicas agree, and is every acknowledged write still there.

Why compare full copies: a digest says *whether* replicas differ; when they do, an operator needs
*what* differs (a node one agent writes and the others refuse, a lost delta), so the copies are
kept and diffed by node and edge name.
"""

from __future__ import annotations

from typing import Any

from tools.chaos.schedule import clock_text



def probe_replicas(session: Any, graph_name: str, timeout_s: float = 2.0) -> dict[str, Any]:
    """Every replica that answers one state query, as an offline DSRGraph copy, by agent name."""
    import zenoh

    from dsr import DSRGraph, wire

    class ProbedCopy(DSRGraph):
        """A member's state as an offline graph, with the ``writers`` table it served (replica -> agent)."""

        served_table: dict[str, str]

    copies: dict[str, Any] = {}
    replies = session.get(wire.state_key(graph_name, "*"), target=zenoh.QueryTarget.ALL,
                          consolidation=zenoh.ConsolidationMode.NONE, timeout=timeout_s)
    for reply in replies:
        if reply.ok is None:
            continue
        message = wire.decode(reply.ok.payload.to_bytes())
        copy = ProbedCopy("probe", graph=graph_name)
        copy.apply_message(message)
        copy.served_table = dict(message.writers)    # what that member vouches for (below)
        copies[message.agent] = copy
    return copies


def unproven_claims(copies: dict[str, Any]) -> list[str]:
    """Claims a member serves in its state's `writers` about ANOTHER member that answered,
    which that member's own table does not make: a replica never serves a claim it cannot
    prove (docs/dsr_wire_format.md, "What a replica serves"), so in a run without a liar this
    is empty."""
    own = {agent: {r for r, a in getattr(copy, "served_table", {}).items() if a == agent}
           for agent, copy in copies.items()}
    found = []
    for agent, copy in copies.items():
        for replica, claimed in getattr(copy, "served_table", {}).items():
            if claimed != agent and claimed in own and replica not in own[claimed]:
                found.append(f"{agent} serves replica {replica} as {claimed!r}, which "
                             f"{claimed!r} does not list")
    return found


def trust_summary(stats: dict[str, Any], copies: dict[str, Any]) -> dict[str, Any]:
    """The trust counters of a run: refusals per member and reason (0 in a run without
    hostile input, restarts included), state fetches, unproven claims served, ACL denials."""
    refusals: dict[str, dict[str, int]] = {}
    fetches: dict[str, dict[str, int]] = {}
    for agent, report in stats.get("members", {}).items():
        counters = report.get("stats", {})
        rejects = {k: v for k, v in (counters.get("rejects") or {}).items() if v}
        if rejects:
            refusals[agent] = rejects
        fetches[agent] = {k: int(counters.get(k, 0)) for k in
                          ("syncs", "anti_entropy", "fetches_postponed", "state_served",
                           "deferred", "forgeries_about_me")}
    router = stats.get("router")
    return {"refusals": refusals, "refusals_total": sum(sum(r.values()) for r in refusals.values()),
            "fetches": fetches, "unproven_claims_served": unproven_claims(copies),
            "router_acl_denied": None if router is None else router.get("acl_denied")}


def describe_divergence(copies: dict[str, Any], limit: int = 4) -> str:
    """Which replicas disagree with the largest group, and on which nodes/edges (for the report)."""
    groups: dict[str, list[str]] = {}
    for agent, copy in copies.items():
        groups.setdefault(copy.digest(), []).append(agent)
    if len(groups) <= 1:
        return ""
    majority = max(groups.values(), key=len)

    def elements(copy: Any) -> dict[str, Any]:
        document = copy.to_document()
        names = {n["id"]: n["name"] for n in document["nodes"]}
        out = {f"node {n['name']}": (n["type"], n["attrs"]) for n in document["nodes"]}
        out |= {f"edge {names.get(e['src'])}-{e['type']}->{names.get(e['dst'])}": e["attrs"] for e in document["edges"]}
        return out

    reference = elements(copies[majority[0]])
    parts = []
    for agents in groups.values():
        if agents is majority:
            continue
        other = elements(copies[agents[0]])
        differ = sorted(k for k in reference.keys() | other.keys() if reference.get(k) != other.get(k))
        parts.append(f"{','.join(sorted(agents))} vs {','.join(sorted(majority))}: "
                     f"{'; '.join(differ[:limit])}{' ...' if len(differ) > limit else ''}")
    return " | ".join(parts)


def lost_writes(graph: Any, loaded: Any, done_seen: set[str], accepted: list[str]) -> list[str]:
    """Every acknowledged write that is not in the final graph, as a sentence each (empty: none).

    ``accepted``: change JSON texts whose requests were answered "accepted"."""
    from agents.world.vocabulary import ActivityState, MissionState, NodeType
    from agents.lib.agenda.changes import AgendaChangeError, apply_change, parse_change

    lost: list[str] = []
    for node in graph.nodes_of_type(NodeType.MISSION):
        mission_id = str(node.attrs.get("mission_id", node.name))
        if mission_id in done_seen and node.attrs.get("state") != MissionState.DONE:
            lost.append(f"mission {mission_id} was done, now {node.attrs.get('state')!r}")
    missing = done_seen - {str(n.attrs.get("mission_id", n.name)) for n in graph.nodes_of_type(NodeType.MISSION)}
    lost += [f"mission {m} was done, now missing" for m in sorted(missing)]
    agenda = graph.get_node_by_name("agenda")
    log = list(agenda.attrs.get("changes", [])) if agenda is not None else []
    for text in accepted:
        count = log.count(text)
        if count != 1:
            lost.append(f"accepted agenda change {text} is {count} times in the agenda's change log")
    scene = loaded.scene
    day = loaded.agenda
    for text in log:
        try:
            day = apply_change(day, parse_change(text), known_objects={o.name for o in scene.objects},
                               known_rooms={r.name for r in scene.rooms})
        except AgendaChangeError as exc:
            lost.append(f"logged agenda change {text} no longer applies: {exc}")
    published = {str(n.attrs.get("activity_id")): n.attrs for n in graph.nodes_of_type(NodeType.ACTIVITY)}
    for activity in day.activities:
        attrs = published.get(activity.id)
        if attrs is None:
            lost.append(f"activity {activity.id} is missing from the DSR")
            continue
        if (float(attrs.get("start_s", -1)), float(attrs.get("end_s", -1))) != (activity.start_s, activity.end_s) \
                or attrs.get("object") != activity.object or (attrs.get("state") == ActivityState.CANCELLED) != activity.cancelled:
            lost.append(f"activity {activity.id} in the DSR ({clock_text(attrs.get('start_s'))}-"
                        f"{clock_text(attrs.get('end_s'))}, {attrs.get('state')}) differs from the agenda log "
                        f"({clock_text(activity.start_s)}-{clock_text(activity.end_s)}, "
                        f"{'cancelled' if activity.cancelled else 'not cancelled'})")
    extra = set(published) - {a.id for a in day.activities}
    lost += [f"activity {a} is in the DSR but not in the agenda log" for a in sorted(extra)]
    return lost
