"""chronav's write policy: the table of who may write what in the DSR, and how agents load it.

Why here and not in ``dsr/``: the DSR enforces any policy it is given but reads no files and knows
no agent names; which agent owns which part of chronav's vocabulary (``vocabulary.py``) is
chronav's business.  The table ships as package data next to this module
(``write_policy.yaml``), so an installed (non-editable) chronav finds it; ``CHRONAV_WRITE_POLICY``
names another file, or ``allow-all`` to switch enforcement off.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

from dsr.errors import PolicyError
from dsr.policy import AllowAll, WritePolicy
from dsr.policy_rules import PolicyDocument, RulePolicy
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
    return load_policy(path)
