"""The router's count of ACL denials, parsed from Zenoh's own trace log (dsr/acl_denials.py).

tests/data/zenoh_acl_trace.log was captured from eclipse-zenoh 1.10.2 (the pinned version):
a router with usrpwd and an ACL denying user `guest` put, delete, reply, queryables and tokens
on `chronav/**`; guest declared a key expression, a queryable and a token, then put 3 times on
`chronav/x/delta/sim_robot` and once on `other/ok` (allowed).  The precomputation blocks Zenoh
writes when a key is declared ("caching permissions for ...") are not messages: 5 denials.
The same path live (router process, `chronav dsr stats`): tests/integration/test_trust_acl.py.
"""

from __future__ import annotations

from dsr.acl_denials import AclDenials
from tests.support import REPO_ROOT

TRACE = (REPO_ROOT / "tests" / "data" / "zenoh_acl_trace.log").read_text().splitlines()


def test_denied_messages_are_counted_by_user_kind_and_key_not_the_precomputation():
    logged: list[str] = []
    denials = AclDenials(logged.append)
    for line in TRACE:
        denials.on_log_line(line)
    report = denials.report()
    assert report["acl_denied"] == 5
    counts = {(d["user"], d["message"], d["key"]): d["count"] for d in report["denials"]}
    assert counts == {("guest", "put", "chronav/x/delta/sim_robot"): 3,
                      ("guest", "declare queryable", "chronav/x/state/agenda"): 1,
                      ("guest", "liveliness token", "chronav/x/members/agenda"): 1}
    assert logged[-1] == ("dsr.router: ACL denied put (ingress) on chronav/x/delta/sim_robot by "
                          "user 'guest' (5 denied so far)")


def test_a_flood_of_denials_is_logged_first_then_summarised():
    logged: list[str] = []
    denials = AclDenials(logged.append)
    line = next(t for t in TRACE if "unauthorized to Put" in t and "Using cached" not in t)
    for _ in range(10_000):
        denials.on_log_line(line)
    assert denials.total == 10_000
    assert 20 <= len(logged) <= 22          # the first 20, then one line per 10 s
    assert all("ACL denied" in text for text in logged)
