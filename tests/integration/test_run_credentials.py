"""A run's router admits only the run's users, and each user writes only under its own agent name.

The router is started exactly as `chronav launch` starts it (tools/system/runs.py: per-run users and
passwords, usrpwd dictionary, generated ACL); the writers are real Zenoh sessions on 127.0.0.1.
The observer accepts every write (no DSR write policy), so what it does not receive was dropped
by the router: on loopback too, a process without an agent's password cannot publish as it.
"""

from __future__ import annotations

import json
import os
import stat
import time
from pathlib import Path

import pytest

from dsr import AllowAll, ZenohSettings, join
from dsr.transport import TransportError
from tests.support import ProcessGroup, free_port, wait_until
from tools.system.runs import Identity, prepare_run_security

pytestmark = pytest.mark.slow

GRAPH = "run_credentials_test"
AGENTS = ("sim_robot", "executive", "agenda")


def settings(endpoint: str, identity: Identity | None) -> ZenohSettings:
    creds = {} if identity is None else {"user": identity.user, "password": identity.password}
    return ZenohSettings(connect=[endpoint], lease_ms=1000, **creds)


def start_run_router(procs: ProcessGroup, run_dir: Path, security) -> str:
    port = free_port()
    log = run_dir / "router.log"
    proc = procs.spawn(["-m", "dsr.router", "--listen", f"tcp/127.0.0.1:{port}", *security.router_args()],
                       log_path=log)
    wait_until(lambda: "dsr.router ready" in (log.read_text() if log.exists() else "") or proc.poll() is not None,
               15, message="run router ready")
    assert proc.poll() is None, log.read_text()
    return f"tcp/127.0.0.1:{port}"


def test_secrets_are_private_files(tmp_path: Path) -> None:
    security = prepare_run_security(tmp_path, GRAPH, AGENTS)
    assert stat.S_IMODE(security.secrets_dir.stat().st_mode) == 0o700
    for path in (security.credentials_file, security.acl_file, *(security.password_file(a) for a in AGENTS)):
        assert stat.S_IMODE(path.stat().st_mode) == 0o600, path
    lines = security.credentials_file.read_text().splitlines()
    assert [line.split(":")[0] for line in lines] == [*AGENTS, "agenda_tool", "reader"]
    assert len({line.split(":")[1] for line in lines}) == len(lines), "every user has its own password"
    env = security.agent_env("executive")
    assert env["CHRONAV_ZENOH_USER"] == "executive"
    assert Path(env["CHRONAV_ZENOH_PASSWORD_FILE"]).read_text().strip() == security.agents["executive"].password
    assert not any(security.agents["executive"].password in arg for arg in security.router_args())
    acl = json.loads(security.acl_file.read_text())["access_control"]
    assert acl["default_permission"] == "deny"
    assert {r["id"]: r["key_exprs"] for r in acl["rules"]}["write_as_executive"] == [f"chronav/{GRAPH}/*/executive"]


def test_each_agent_key_space_belongs_to_its_credentials(procs: ProcessGroup, tmp_path: Path) -> None:
    security = prepare_run_security(tmp_path, GRAPH, AGENTS)
    endpoint = start_run_router(procs, tmp_path, security)

    # no credentials, or a wrong password: no session at all
    with pytest.raises(TransportError), join("sim_robot", graph=GRAPH, settings=settings(endpoint, None),
                                             sync_timeout=2):
        pass
    with pytest.raises(TransportError), join("sim_robot", graph=GRAPH,
                                             settings=settings(endpoint, Identity("sim_robot", "guess")),
                                             sync_timeout=2):
        pass

    observer_settings = settings(endpoint, security.agents["agenda"])
    with join("agenda", graph=GRAPH, settings=observer_settings, policy=AllowAll()) as observer:
        # Impostors: authenticated, their sessions work (they read the graph), their writes go nowhere.
        impostors = [("sim_robot", security.tool), ("sim_robot", security.agents["executive"]),
                     ("executive", security.reader), ("agenda_tool-evil", security.agents["sim_robot"])]
        for claimed, identity in impostors:
            with join(claimed, graph=GRAPH, settings=settings(endpoint, identity), sync_timeout=2,
                      policy=AllowAll()) as impostor:
                impostor.insert_node("laser", f"forged/{claimed}/{identity.user}")
                impostor.flush()
        # The rightful owners of those names.
        with join("sim_robot", graph=GRAPH, settings=settings(endpoint, security.agents["sim_robot"]),
                  sync_timeout=2, policy=AllowAll()) as robot, \
                join("agenda_tool-desk", graph=GRAPH, settings=settings(endpoint, security.tool),
                     sync_timeout=2, policy=AllowAll()) as desk:
            robot.insert_node("laser", "laser")
            desk.insert_node("agenda_request", "agenda_request/desk", {"state": "pending"})
            robot.flush()
            desk.flush()
            wait_until(lambda: observer.get_node_by_name("laser") is not None
                       and observer.get_node_by_name("agenda_request/desk") is not None, 10,
                       message="the rightful writes")
            time.sleep(0.5)     # anything the impostors sent would have arrived long before
            names = {n.name for n in observer.nodes()}
            assert not {n for n in names if n.startswith("forged/")}, names
            assert observer.replica.stats.rejected == 0     # dropped by the router, not by the replica
    assert os.environ.get("CHRONAV_ZENOH_PASSWORD") is None
