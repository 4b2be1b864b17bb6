"""AGGL-style graph grammars for chronav: parse rule files, match patterns, plan missions.

Pipeline (one module per step): ``parser`` (text -> ``model``, via ``aggl.lark``, ``transform``,
``validate``) -> ``world`` (indexed graph + search states) -> ``matcher`` / ``formulas`` ->
``rewrite`` -> ``planner`` (A*, with ``heuristics`` and ``relevance``; ``diagnosis`` says why there
is no plan) ; ``missions`` turns mission strings into targets; ``agm_world`` reads and writes AGM's
world XML. See docs/grammar.md.
"""

from grammar.diagnosis import Blocker, Diagnosis, Witness
from grammar.errors import GrammarError, GrammarWarning, MissionError, PlanningError, SourcePos
from grammar.missions import Mission, parse_mission, plan_mission, with_mission_node
from grammar.model import Grammar, Pattern, PatternLink, PatternNode, Rule, Target
from grammar.parser import default_grammar_path, load_grammar, load_target, parse_grammar, parse_target
from grammar.planner import NoPlan, Plan, Planner, PlanStep, plan

__all__ = [
    "Blocker", "Diagnosis", "Grammar", "GrammarError", "GrammarWarning", "Witness", "Mission", "MissionError", "NoPlan", "Pattern", "PatternLink", "PatternNode",
    "Plan", "PlanStep", "Planner", "PlanningError", "Rule", "SourcePos", "Target", "default_grammar_path",
    "load_grammar", "load_target", "parse_grammar", "parse_mission", "parse_target", "plan", "plan_mission",
    "with_mission_node",
]
