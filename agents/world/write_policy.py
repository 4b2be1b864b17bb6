"""chronav's write policy: the table of who may write what in the DSR, and how agents load it.

Why here and not in ``dsr/``: the DSR enforces any policy it is given but reads no files and knows
no agent names; which agent owns which part of chronav's vocabulary (``vocabulary.py``) is
chronav's business.  The table ships as package data next to this module
(``write_policy.yaml``), so an installed (non-editable) chronav finds it; ``CHRONAV_WRITE_POLICY``
names another file, or ``allow-all`` to switch enforcement off.

The table is generated from chronav's own vocabulary (``vocabulary_rules``; the grants of
installed agent plug-ins are added when it is loaded, ``with_plugin_grants``): each grant names its attributes
(no ``*``), and a creator may give at creation only the attributes the vocabulary lists.  The
shipped YAML is kept for operators to read and edit a copy of; ``tests/unit/test_vocabulary.py``
fails when it differs from what the vocabulary generates.  Regenerate it with
``python -m agents.world.write_policy > agents/world/write_policy.yaml``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from dsr.errors import PolicyError
from dsr.policy import AllowAll, WritePolicy
from dsr.policy_rules import FORMAT, PolicyDocument, Rule, RulePolicy
from agents.world.vocabulary import EdgeSpec, NodeSpec, Vocabulary, own_vocabulary, vocabulary
from scenes.yamlio import SourceError, load_located_file, validate_located

ENV_POLICY = "CHRONAV_WRITE_POLICY"
DEFAULT_POLICY_FILE = Path(__file__).with_name("write_policy.yaml")
_ALLOW_ALL_WORDS = ("allow-all", "off")


def load_policy(path: str | Path) -> RulePolicy:
    """Read and validate a policy file; PolicyError says `file:line:col: key: problem`."""
    try:
        located = load_located_file(path)
        if not isinstance(located.data, dict):
            raise SourceError(str(path), 1, 1, "", "a write-policy file is a YAML mapping with `format` and `rules`")
        document = validate_located(PolicyDocument, located)
    except SourceError as exc:
        raise PolicyError(str(exc)) from None
    return RulePolicy(document.rules, source=str(path))


def policy_from_env(environ: Mapping[str, str] | None = None) -> WritePolicy:
    """The policy agents run with: CHRONAV_WRITE_POLICY = a YAML file, or `allow-all`/`off`;
    unset = the shipped table.  Raises PolicyError naming the file, line and key."""
    env = os.environ if environ is None else environ
    value = (env.get(ENV_POLICY) or "").strip()
    if value.lower() in _ALLOW_ALL_WORDS:
        return AllowAll()
    path = Path(value) if value else DEFAULT_POLICY_FILE
    if not path.is_file():
        where = f"{ENV_POLICY}={value!r}" if value else f"default policy {path}"
        raise PolicyError(f"{where}: no such file (set {ENV_POLICY} to a policy YAML file, or to 'allow-all')")
    return with_plugin_grants(load_policy(path))


def with_plugin_grants(policy: RulePolicy, vocab: Vocabulary | None = None) -> RulePolicy:
    """``policy`` with the grants of the installed agent plug-ins added (what they declared they
    write, and their heartbeats), taken from the vocabulary of this installation.

    Why at load and not in the file: the shipped table is chronav's own (generated, tested); a
    plug-in's grants come with its installation, alike on every machine that has it installed.  A
    replica on a machine without it holds no grant for that agent and drops its writes: safe."""
    vocab = vocabulary() if vocab is None else vocab
    own = set(own_vocabulary().names)
    plugins = [name for name in vocab.names if name not in own]
    if not plugins:
        return policy
    rules = [Rule.model_validate(grant) for grant in _grants(vocab, set(plugins))]
    return RulePolicy([*policy.rules, *rules], source=f"{policy.source} + agent plug-ins {', '.join(plugins)}")


# ------------------------------------------------------------------ generated from the vocabulary
def _node_grants(spec: NodeSpec) -> list[dict[str, Any]]:
    """One grant per writer of ``spec``'s type: create/delete as the vocabulary says, the
    attributes it may set, and those it may only give at creation."""
    writers: list[str] = [*spec.creators, *spec.may_delete]
    for attr in spec.attrs.values():
        writers += [*attr.writers, *attr.init_by]
    grants = []
    for writer in dict.fromkeys(writers):
        ops = [op for op, who in (("create", spec.creators), ("delete", spec.may_delete)) if writer in who]
        attrs = [str(key) for key, attr in spec.attrs.items() if writer in attr.writers]
        if not ops and not attrs:
            continue
        grant: dict[str, Any] = {"writers": [writer], "nodes": [str(spec.type)], "ops": ops, "attrs": attrs}
        if "create" in ops:
            grant["init_attrs"] = [str(key) for key, attr in spec.attrs.items() if writer in attr.init_by]
            values = spec.init_values.get(writer)
            if values:
                grant["init_values"] = {str(k): [str(v) for v in vs] for k, vs in values.items()}
        grants.append(grant)
    return grants


def _edge_grant(spec: EdgeSpec) -> dict[str, Any]:
    return {"writers": list(spec.writers), "edges": [str(spec.type)], "from": [str(t) for t in spec.src],
            "to": [str(t) for t in spec.dst], "ops": ["create", "delete"] if spec.delete else ["create"],
            "attrs": [str(key) for key in spec.attrs], "init_attrs": []}


def _grants(vocab: Vocabulary, only: set[str] | None = None) -> list[dict[str, Any]]:
    """``vocab``'s grants as plain data, in its order (those of the writers ``only`` when given);
    grants that differ only by writer are merged (every agent's heartbeat: one grant)."""
    grants: list[dict[str, Any]] = []
    for spec in vocab.nodes.values():
        for grant in _node_grants(spec):
            if only is not None and grant["writers"][0] not in only:
                continue
            same = next((g for g in grants if {**g, "writers": None} == {**grant, "writers": None}), None)
            if same is None:
                grants.append(grant)
            else:
                same["writers"] += grant["writers"]
    grants += [_edge_grant(spec) for spec in vocab.edges if only is None or set(spec.writers) <= only]
    return grants


def vocabulary_grants() -> list[dict[str, Any]]:
    """The shipped write policy as plain data: chronav's core vocabulary and its own agents."""
    return _grants(own_vocabulary())


def vocabulary_rules() -> list[Rule]:
    """The rules the vocabulary declares: what ``write_policy.yaml`` must hold."""
    return [Rule.model_validate(grant) for grant in vocabulary_grants()]


_HEADER = """\
# chronav write policy: who may write what in the DSR graph.
#
# GENERATED from the vocabulary (agents/world/vocabulary.py) by
#   python -m agents.world.write_policy > agents/world/write_policy.yaml
# tests/unit/test_vocabulary.py fails when this file and the vocabulary differ: change the
# vocabulary, then regenerate.  (CHRONAV_WRITE_POLICY=<file> runs the agents with another table,
# =allow-all with none.)
#
# Every replica of every agent checks each remote delta and state against this table before
# merging it (dsr/policy_rules.py): a delta with a refused write is dropped whole, a state keeps
# only the writes its writers were allowed to make (dsr/state_review.py); refusals are logged and
# counted (replica.stats.rejected_policy, `chronav dsr stats`).  Anything not granted here is refused.
#
# A rule grants `writers` some `ops` (create, delete) and the attributes `attrs` (set at any time)
# on `nodes` or `edges` of the listed types; edge rules restrict the end node types with `from` /
# `to`.  `create` brings the initial values of `attrs` and `init_attrs` only, and of an
# `init_values` key only the listed values.  Deleting a node deletes its edges.
"""


def render_policy_yaml() -> str:
    """The shipped ``write_policy.yaml``, as the vocabulary generates it."""
    import yaml

    body = yaml.safe_dump({"format": FORMAT, "rules": vocabulary_grants()}, sort_keys=False,
                          default_flow_style=None, width=120)
    return _HEADER + body


if __name__ == "__main__":
    import sys

    sys.stdout.write(render_policy_yaml())
