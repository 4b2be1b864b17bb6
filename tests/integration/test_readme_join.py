"""The README's `dsr.join` example runs as written once the router it names is started (issue 39:
the example used to need a router the README never mentioned)."""

from __future__ import annotations

import contextlib
import io
import re

from tests.integration.dsr_support import start_router
from tests.support import REPO_ROOT


def test_readme_join_example_runs_against_the_router_it_names(procs, tmp_path, monkeypatch) -> None:
    readme = (REPO_ROOT / "README.md").read_text()
    section = readme[readme.index("## The DSR"):]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    code = next(b for b in blocks if "dsr.join" in b)
    assert "python -m dsr.router" in code, "the example says which router it needs"
    endpoint, _ = start_router(procs, tmp_path)     # the README's router, on a free port
    monkeypatch.setenv("CHRONAV_ZENOH_CONNECT", endpoint)
    monkeypatch.setenv("CHRONAV_GRAPH", f"readme_{tmp_path.name}")
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README.md", "exec"), {})
    expected = code.strip().splitlines()[-1].split("#", 1)[1].strip()
    assert out.getvalue().strip() == expected
