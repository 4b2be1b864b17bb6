"""Zenoh authentication + access control in front of the DSR (deploy/acl.json5, real processes).

The router requires user/password (deploy/credentials.example.txt) and applies the shipped ACL:
every user may read, each user may write only under its own agent names.  Shown here:
- no credentials or a wrong password: the session cannot even open;
- an authenticated camera user cannot write deltas under the agenda's name (a forged activity)
  nor inject an agenda change (a request under an `agenda_tool-*` name), although its session
  works (it reads the graph) and it can write under its own name;
- the staff user's agenda request and the camera's person arrive; a late joiner's state
  transfer does not bring the forged nodes either (the impostor may not serve state).
TLS (tls/ endpoints, certificates from deploy/make_certs.sh) is covered at the end.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from dsr import ZenohSettings, join
from dsr.transport import TransportError
from tests.integration.fault_support import spawn_script, status_of
from tests.support import REPO_ROOT, free_port, wait_until

pytestmark = pytest.mark.slow

DEPLOY = REPO_ROOT / "deploy"
CREDENTIALS = DEPLOY / "credentials.example.txt"
PASSWORDS = dict(line.split(":", 1) for line in CREDENTIALS.read_text().split())


def start_secure_router(procs, log_dir: Path, *extra: str) -> tuple[str, object]:
    port = free_port()
    log = log_dir / "router.log"
    proc = procs.spawn(["-m", "dsr.router", "--listen", f"tcp/127.0.0.1:{port}",
                        "--credentials", str(CREDENTIALS), "--acl", str(DEPLOY / "acl.json5"),
                        *extra], log_path=log)
    wait_until(lambda: "dsr.router ready" in (log.read_text() if log.exists() else "")
               or proc.poll() is not None, 15, message="secure router ready")
    assert proc.poll() is None, log.read_text()
    return f"tcp/127.0.0.1:{port}", proc


def user_env(user: str, password: str | None = None) -> dict[str, str]:
    return {"CHRONAV_ZENOH_USER": user, "CHRONAV_ZENOH_PASSWORD": password or PASSWORDS[user],
            "CHRONAV_ZENOH_LEASE_MS": "1000"}


def names(path: Path) -> set[str]:
    return set(status_of(path).get("names") or ())


def test_sessions_without_credentials_cannot_open(procs, tmp_path):
    endpoint, _ = start_secure_router(procs, tmp_path)
    for settings in (ZenohSettings(connect=[endpoint]),
                     ZenohSettings(connect=[endpoint], user="camera1", password="wrong"),
                     ZenohSettings(connect=[endpoint], user="nobody", password="x")):
        with pytest.raises(TransportError, match="cannot open Zenoh session"), \
                join("agenda", settings=settings, sync_timeout=2):
            pass
    with join("monitor", settings=ZenohSettings(connect=[endpoint], user="monitor",
                                                password=PASSWORDS["monitor"]),
              read_only=True, sync_timeout=2) as graph:
        assert graph.replica.session.info.routers_zid()


def test_acl_stops_forged_deltas_and_agenda_injection(procs, tmp_path):
    endpoint, _ = start_secure_router(procs, tmp_path)
    _, agenda = spawn_script(procs, tmp_path, "agenda", connect=endpoint, env=user_env("server"),
                             script=[{"op": "insert", "type": "activity", "name": "activity/real",
                                      "attrs": {"state": "scheduled"}}])
    wait_until(lambda: "activity/real" in names(agenda), 20, message="agenda joined")

    # camera1 is authenticated but may write only as human_observer.
    wait_real = {"op": "wait", "names": ["activity/real"]}
    _, impostor = spawn_script(procs, tmp_path, "agenda", connect=endpoint, tag="-impostor",
                               env=user_env("camera1"), script=[wait_real, {
                                   "op": "insert", "type": "activity", "name": "activity/forged",
                                   "attrs": {"state": "running"}}])
    _, injector = spawn_script(procs, tmp_path, "agenda_tool-evil", connect=endpoint,
                               env=user_env("camera1"), script=[wait_real, {
                                   "op": "insert", "type": "agenda_request",
                                   "name": "agenda_request/forged",
                                   "attrs": {"change": '{"op": "cancel", "id": "a1"}',
                                             "state": "pending", "requested_by": "evil"}}])
    # Their sessions work: they read the graph (activity/real) and applied their writes locally.
    wait_until(lambda: {"activity/real", "activity/forged"} <= names(impostor)
               and {"activity/real", "agenda_request/forged"} <= names(injector), 20,
               message="impostors connected and wrote locally")

    _, camera = spawn_script(procs, tmp_path, "human_observer", connect=endpoint,
                             env=user_env("camera1"),
                             script=[{"op": "insert", "type": "person", "name": "alice"}])
    _, desk = spawn_script(procs, tmp_path, "agenda_tool-desk", connect=endpoint,
                           env=user_env("staff"), script=[{
                               "op": "insert", "type": "agenda_request",
                               "name": "agenda_request/desk",
                               "attrs": {"change": '{"op": "cancel", "id": "a1"}',
                                         "state": "pending", "requested_by": "desk"}}])
    wait_until(lambda: {"alice", "agenda_request/desk"} <= names(agenda), 20,
               message="authorised writes reaching the agenda")
    time.sleep(0.5)   # anything still in flight from the impostors would have arrived by now
    seen = names(agenda)
    assert "activity/forged" not in seen and "agenda_request/forged" not in seen
    stats = status_of(agenda)["stats"]
    # Dropped by the router: the forged deltas never reached the replica, not even to be refused.
    assert stats["rejected"] == 0 and stats["rejected_policy"] == 0, stats
    # ... but counted there, and visible: `chronav dsr stats` and the router's log (issue #31)
    shown = subprocess.run(
        [sys.executable, "-m", "tools.cli", "dsr", "stats", "--json", "--connect", endpoint],
        capture_output=True, text=True, timeout=60, cwd=REPO_ROOT,
        env={**os.environ, **user_env("monitor")})
    assert shown.returncode == 0, shown.stderr
    router = json.loads(shown.stdout)["router"]
    denied = {(d["user"], d["message"], d["key"]) for d in router["denials"]}
    assert ("camera1", "put", "chronav/chronav/delta/agenda") in denied, router
    assert ("camera1", "put", "chronav/chronav/delta/agenda_tool-evil") in denied, router
    assert router["acl_denied"] >= 2
    assert "ACL denied put (ingress) on chronav/chronav/delta/agenda by user 'camera1'" in \
        (tmp_path / "router.log").read_text()

    # A late joiner gets the graph by state transfer: the impostors may not serve state.
    _, late = spawn_script(procs, tmp_path, "monitor", connect=endpoint, env=user_env("monitor"))
    wait_until(lambda: {"alice", "agenda_request/desk", "activity/real"} <= names(late), 20,
               message="late joiner synchronised")
    time.sleep(0.5)
    assert not {"activity/forged", "agenda_request/forged"} & names(late)
    assert status_of(late)["digest"] == status_of(agenda)["digest"]


def make_certs(directory: Path) -> Path:
    if shutil.which("openssl") is None:
        pytest.skip("openssl is needed to make test certificates")
    subprocess.run(["sh", str(DEPLOY / "make_certs.sh"), str(directory), "127.0.0.1", "localhost",
                    "--client", "robot"], check=True, capture_output=True, timeout=120)
    return directory


def test_tls_with_credentials_and_mutual_tls(procs, tmp_path):
    certs = make_certs(tmp_path / "tls")
    port = free_port()
    log = tmp_path / "router.log"
    router = procs.spawn(["-m", "dsr.router", "--listen", f"tls/127.0.0.1:{port}",
                          "--credentials", str(CREDENTIALS), "--tls-cert", str(certs / "router.pem"),
                          "--tls-key", str(certs / "router.key"), "--tls-root-ca",
                          str(certs / "ca.pem"), "--mtls"], log_path=log)
    wait_until(lambda: "dsr.router ready" in (log.read_text() if log.exists() else "")
               or router.poll() is not None, 15, message="TLS router ready")
    assert router.poll() is None, log.read_text()
    endpoint = f"tls/localhost:{port}"
    env = {**user_env("robot"), "CHRONAV_ZENOH_TLS_ROOT_CA": str(certs / "ca.pem"),
           "CHRONAV_ZENOH_TLS_CERT": str(certs / "robot.pem"),
           "CHRONAV_ZENOH_TLS_KEY": str(certs / "robot.key"), "CHRONAV_ZENOH_MTLS": "1",
           "CHRONAV_WRITE_POLICY": "allow-all"}
    _, writer = spawn_script(procs, tmp_path, "sim_robot", connect=endpoint, env=env,
                             script=[{"op": "insert", "type": "robot", "name": "robot"}])
    _, reader = spawn_script(procs, tmp_path, "executive", connect=endpoint, env=env)
    wait_until(lambda: "robot" in names(reader) and "robot" in names(writer), 20,
               message="replication over mutual TLS")
    good = {"user": "robot", "password": PASSWORDS["robot"]}
    refused = [
        ZenohSettings(connect=[endpoint], **good),                          # no CA: untrusted
        ZenohSettings(connect=[endpoint], tls_root_ca=certs / "ca.pem", **good),  # no client cert
        ZenohSettings(connect=[f"tcp/127.0.0.1:{port}"], **good),           # plain TCP
    ]
    for settings in refused:
        with pytest.raises(TransportError), join("intruder", settings=settings, sync_timeout=2):
            pass
