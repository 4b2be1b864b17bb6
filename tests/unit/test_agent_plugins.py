"""Agents as plug-ins (``chronav.agents``, agents/lib/agent_plugins.py): chronav's six registered as
an outside package's are, and what an outside agent declares joining the vocabulary and the write
policy, or being refused at start naming the plug-in, its package and why while the rest runs.

The outside agents are a real installed distribution on sys.path (tests/plugin_fixtures.py),
found through importlib.metadata as a pip-installed package is."""

from __future__ import annotations

import pytest

from agents.lib import registry
from agents.lib.agent_plugins import AgentSpec, EdgeDecl, NodeDecl
from agents.runtime.checked_graph import CheckedGraph
from agents.world import vocabulary as vocab
from agents.world.write_policy import DEFAULT_POLICY_FILE, load_policy, with_plugin_grants
from dsr import DSRGraph
from dsr.errors import WriteRefusedError
from dsr.writes import Write
from tests.plugin_fixtures import install_fake_plugins
from tests.support import REPO_ROOT
# imported before any test installs the fake agents: its defaults (every registered agent) stay chronav's
from tools.offline_agents import OfflineAgents

PACKAGE = "chronav-test-agents"
MODULE = '''"""Agent plug-ins for the tests: one good, the others each broken in one way."""
from agents.lib.agent_plugins import AgentSpec, EdgeDecl, NodeDecl
from agents.runtime.base import Agent


class Crasher(Agent):
    """Raises on its second step."""

    kind = "crasher"

    def setup(self, graph, recorder):
        self.steps = 0

    def step(self):
        self.steps += 1
        if self.steps == 2:
            raise RuntimeError("boom")


def crasher():
    return AgentSpec(name="crasher", process="chronav_test_agents", agent_class="chronav_test_agents:Crasher",
                     round_order=60)


def _spec(name, **kw):
    return AgentSpec(name=name, process="chronav_test_agents", agent_class="chronav_test_agents:Scribe",
                     round_order=35, **kw)


def scribe():
    """Writes scribbles about people."""
    return _spec("scribe", nodes=(NodeDecl("scribble", {"text": "str", "time_s": "float"}),),
                 edges=(EdgeDecl("scribbled", ("scribble",), ("person",)),
                        EdgeDecl("RT", ("world",), ("scribble",), {"x": "float", "y": "float", "theta": "float"})))


def claims_person():
    return _spec("claims_person", nodes=(NodeDecl("person", {"mood": "str"}),))


def claims_robot_pose():
    return _spec("claims_robot_pose", edges=(EdgeDecl("RT", ("world",), ("robot",), {"x": "float"}),))


def wrong_name():
    return _spec("somebody_else")


def bad_kind():
    return _spec("bad_kind", nodes=(NodeDecl("jot", {"text": "double"}),))


def not_a_spec():
    return {"name": "not_a_spec"}


def lost_process():
    return AgentSpec(name="lost_process", process="chronav_no_such_module.agent",
                     agent_class="chronav_test_agents:Scribe", round_order=60)


def bad_class():
    return AgentSpec(name="bad_class", process="chronav_test_agents",
                     agent_class="chronav_test_agents:NoSuchClass", round_order=60)
'''
ENTRIES = {"chronav.agents": {name: f"chronav_test_agents:{name}" for name in (
    "scribe", "claims_person", "claims_robot_pose", "wrong_name", "bad_kind", "not_a_spec", "bad_class",
    "lost_process", "crasher")}
    | {"missing_module": "chronav_no_such_module:describe"}}
OWN = ("sim_robot", "object_recognition", "agenda", "human_observer", "executive", "social_navigation")


def _forget() -> None:
    registry.clear()
    vocab.vocabulary.cache_clear()
    vocab.own_vocabulary.cache_clear()


@pytest.fixture
def outside(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(install_fake_plugins(tmp_path / "site", ENTRIES, PACKAGE, MODULE,
                                                         "chronav_test_agents")))
    _forget()
    yield vocab.vocabulary()
    _forget()


def test_chronav_registers_its_six_agents_in_round_order_like_any_package() -> None:
    own = vocab.own_vocabulary()
    assert own.names == OWN
    assert {registry.entry("agent", name).package for name in OWN} == {"chronav"}
    assert own.spec("sim_robot").lockstep_options == ("busy_rate=0", "perception_lockstep=1")
    assert own.spec("social_navigation").process == "agents.social_navigation"
    assert [s.name for s in own.agents if s.perceiver] == ["object_recognition", "agenda", "human_observer"]
    assert set(own.nodes[vocab.NodeType.HEARTBEAT].creators) == {*OWN, vocab.ROS_BRIDGE}


def test_an_outside_agents_types_join_the_vocabulary_and_broken_ones_are_refused(outside) -> None:
    assert outside.names == (*OWN[:4], "scribe", *OWN[4:], "bad_class", "crasher", "lost_process")   # 35, then 60
    reasons = {r.name: (r.package, r.reason) for r in outside.refused}
    assert set(reasons) == {"claims_person", "claims_robot_pose", "wrong_name", "bad_kind", "not_a_spec",
                            "missing_module"}
    assert {package for package, _ in reasons.values()} == {PACKAGE}
    assert reasons["claims_person"][1] == \
        "node type 'person' belongs to human_observer: an agent declares only new types"
    assert "edge type 'RT' belongs to" in reasons["claims_robot_pose"][1]
    assert "named 'somebody_else', not 'wrong_name'" in reasons["wrong_name"][1]
    assert "kind 'double'" in reasons["bad_kind"][1]
    assert "returned a dict without the fields of an AgentSpec" in reasons["not_a_spec"][1]
    assert "cannot import chronav_no_such_module:describe" in reasons["missing_module"][1]
    # the declared types are the scribe's alone; chronav's own vocabulary (the shipped table's) is untouched
    assert outside.nodes["scribble"].creators == ("scribe",)
    assert "scribble" not in vocab.own_vocabulary().nodes
    vocab.check_attrs("scribble", {"text": "hello", "time_s": 1.0})
    vocab.check_edge("scribbled", {})
    with pytest.raises(vocab.VocabularyError, match="no attribute 'mood'"):
        vocab.check_attrs("scribble", {"mood": "x"})


def test_the_write_policy_grants_what_it_declared_and_nothing_else(outside) -> None:
    shipped = load_policy(DEFAULT_POLICY_FILE)
    policy = with_plugin_grants(shipped)
    assert "agent plug-ins" in policy.source and "scribe" in policy.source
    assert policy.allowed(Write("scribe", "node", "scribble", "create"))
    assert policy.allowed(Write("scribe", "node", "scribble", "attr", attr="text"))
    assert policy.allowed(Write("scribe", "edge", "scribbled", "create", src="scribble", dst="person"))
    assert policy.allowed(Write("scribe", "edge", "RT", "create", src="world", dst="scribble"))
    assert policy.allowed(Write("scribe", "node", "heartbeat", "attr", attr="beat"))
    assert not policy.allowed(Write("scribe", "node", "person", "create"))            # the observer's
    assert not policy.allowed(Write("scribe", "edge", "RT", "create", src="world", dst="robot"))
    assert not policy.allowed(Write("scribe", "node", "scribble", "attr", attr="mood"))  # undeclared
    assert not policy.has_rights("claims_person")                                     # refused: no grant
    # a replica whose machine lacks the plug-in runs the shipped table: it refuses all of the scribe's writes
    assert not shipped.has_rights("scribe")


def test_an_agent_writing_an_undeclared_or_anothers_type_is_refused_and_the_graph_is_unchanged(outside) -> None:
    graph = DSRGraph(agent="scribe")
    graph.local_policy = with_plugin_grants(load_policy(DEFAULT_POLICY_FILE))
    checked = CheckedGraph(graph, "scribe")
    before = graph.digest()
    assert checked.insert_node("memo", "memo/1", {"text": "x"}) is None         # a type nobody declared
    assert "unknown node type 'memo'" in checked.last_refusal
    assert checked.insert_node("scribble", "s/0", {"mood": "x"}) is None        # an attribute it did not declare
    assert checked.refused == 2 and "a scribble node has no attribute 'mood'" in checked.last_refusal
    with pytest.raises(WriteRefusedError, match="person"):                       # the observer's type
        checked.insert_node("person", "resident", {"role": "resident"})
    assert graph.digest() == before
    note = checked.insert_node("scribble", "s/1", {"text": "hello", "time_s": 3.0})
    assert note is not None and graph.get_node_by_name("s/1").attrs["text"] == "hello"


def test_take_in_is_pure_and_refuses_a_claim_on_chronavs_types() -> None:
    ours = AgentSpec("jotter", "pkg.jotter", "pkg.jotter:Jotter", 60, nodes=(NodeDecl("jot", {"text": "str"}),),
                     edges=(EdgeDecl("RT", ("world",), ("jot",), {"x": "float"}),))
    greedy = AgentSpec("greedy", "pkg.greedy", "pkg.greedy:Greedy", 60,
                       edges=(EdgeDecl("in", ("person",), ("room",)),))
    taken = vocab.take_in([(ours, "pkg"), (greedy, "pkg")])
    assert taken.names == ("jotter",) and taken.nodes["jot"].creators == ("jotter",)
    [refusal] = taken.refused
    assert (refusal.name, refusal.package) == ("greedy", "pkg")
    assert "edge type 'in' belongs to" in refusal.reason and "human_observer" in refusal.reason
    again = vocab.take_in([(ours, "pkg"), (greedy, "pkg")])
    assert again.nodes == taken.nodes and again.edges == taken.edges


def test_plugins_lists_agents_and_in_process_leaves_out_a_class_it_cannot_import(outside, caplog) -> None:
    from tools.inprocess import agent_classes, lockstep_options, round_order
    from tools.plugins_cli import inventory

    rows = {r["name"]: r for r in inventory() if r["kind"] == "agent"}
    assert rows["scribe"]["status"] == "ok" and rows["scribe"]["summary"] == "Writes scribbles about people."
    assert rows["claims_person"]["status"] == "refused" and "belongs to human_observer" in rows["claims_person"]["reason"]
    assert rows["executive"]["package"] == "chronav" and rows["executive"]["status"] == "ok"
    assert "scribe" in round_order() and lockstep_options()["sim_robot"] == ["busy_rate=0", "perception_lockstep=1"]
    assert agent_classes(["bad_class"]) == {}
    assert "agent plug-in 'bad_class' from package 'chronav-test-agents' refused: cannot import" in caplog.text



def test_a_launch_refuses_an_agent_whose_process_module_is_missing_and_starts_the_rest(outside, caplog) -> None:
    from tools.launch import process_agents

    assert "lost_process" in outside.names                  # its description is fine...
    started = [spec.name for spec in process_agents()]
    assert "lost_process" not in started and {*OWN, "scribe", "crasher"} <= set(started)   # ...its module is not
    assert ("agent plug-in 'lost_process' from package 'chronav-test-agents' refused: "
            "no module chronav_no_such_module.agent to run as its process") in caplog.text


def test_an_agent_plugin_that_raises_leaves_an_in_process_run_and_the_others_go_on(outside, tmp_path) -> None:
    with OfflineAgents(REPO_ROOT / "tests" / "data" / "eval_tiny.yaml", tmp_path, agents=("sim_robot",)) as run:
        crasher = run.add("crasher")
        run.tick()
        run.tick()                                   # its second step raises: no AgentError, it leaves
        assert run.lockstep.dropped["crasher"] == (
            "agent plug-in 'crasher' from package 'chronav-test-agents' failed in step: RuntimeError: boom; "
            "it left the run, the others go on")
        assert crasher not in run.lockstep.agents and crasher.steps == 2
        run.skip_to("10:00")
        for _ in range(5):
            run.tick()                               # the simulator goes on, the crasher is not stepped
        assert crasher.steps == 2 and vocab.now_s(run.graph) >= 36000.0


def test_a_launch_goes_on_when_its_supervisor_gives_up_on_an_agent_plugin(outside) -> None:
    import time
    from types import SimpleNamespace

    from tools.launch import _run_over

    def over(given_up: list[str]) -> bool:
        run = SimpleNamespace(missions={}, spec=SimpleNamespace(missions=["cross"]), interrupted=False,
                              timed_out=False, started=time.monotonic(),
                              supervisor=SimpleNamespace(given_up=lambda: given_up))
        return _run_over(run, SimpleNamespace(requested=False), {"clock_finished": False}, 900.0)

    assert not over([]) and not over(["crasher"])
    assert over(["executive"]) and over(["router"]) and over(["crasher", "sim_robot"])
