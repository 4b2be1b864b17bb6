"""Multi-host Zenoh settings: credentials, TLS, ACL, lease from env / files, and deploy/ examples."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from dsr import ConfigError, ZenohSettings
from dsr.config import check_credentials_file, load_acl
from dsr.router import parse_args, router_settings
from tests.support import REPO_ROOT

DEPLOY = REPO_ROOT / "deploy"


def get(conf, key):
    return json.loads(conf.get_json(key))


@pytest.fixture
def files(tmp_path: Path) -> dict[str, Path]:
    made = {}
    for name in ("ca.pem", "me.pem", "me.key"):
        made[name] = tmp_path / name
        made[name].write_text("-----BEGIN CERTIFICATE-----\n")
    made["creds"] = tmp_path / "creds.txt"
    made["creds"].write_text("robot:pw1\ncamera1:pw2\n")
    made["password"] = tmp_path / "robot.password"
    made["password"].write_text("s3cret\n")
    return made


def test_credentials_tls_and_lease_from_the_environment(files):
    env = {"CHRONAV_ZENOH_CONNECT": "tls/10.0.0.1:7447", "CHRONAV_ZENOH_USER": "robot",
           "CHRONAV_ZENOH_PASSWORD_FILE": str(files["password"]),
           "CHRONAV_ZENOH_TLS_ROOT_CA": str(files["ca.pem"]),
           "CHRONAV_ZENOH_TLS_CERT": str(files["me.pem"]),
           "CHRONAV_ZENOH_TLS_KEY": str(files["me.key"]), "CHRONAV_ZENOH_MTLS": "1",
           "CHRONAV_ZENOH_LEASE_MS": "1500"}
    settings = ZenohSettings.from_env(env)
    conf = settings.to_zenoh_config()
    assert get(conf, "transport/auth/usrpwd/user") == "robot"
    assert get(conf, "transport/auth/usrpwd/password") == "s3cret"
    assert get(conf, "transport/link/tls/root_ca_certificate") == str(files["ca.pem"].resolve())
    assert get(conf, "transport/link/tls/connect_certificate") == str(files["me.pem"].resolve())
    assert get(conf, "transport/link/tls/enable_mtls") is True
    assert get(conf, "transport/link/tx/lease") == 1500
    assert get(conf, "connect/endpoints") == ["tls/10.0.0.1:7447"]
    text = settings.describe() + repr(settings)
    assert "s3cret" not in text and "user=robot" in text and "mtls" in text


@pytest.mark.parametrize(("env", "var"), [
    ({"CHRONAV_ZENOH_USER": "robot"}, "CHRONAV_ZENOH_USER"),              # no password
    ({"CHRONAV_ZENOH_TLS_CERT": "/nope.pem"}, "CHRONAV_ZENOH_TLS_CERT"),
    ({"CHRONAV_ZENOH_ACL": "/nope.json5"}, "CHRONAV_ZENOH_ACL"),
    ({"CHRONAV_ZENOH_CREDENTIALS": "/nope.txt"}, "CHRONAV_ZENOH_CREDENTIALS"),
    ({"CHRONAV_ZENOH_LEASE_MS": "ten"}, "CHRONAV_ZENOH_LEASE_MS"),
    ({"CHRONAV_ZENOH_LEASE_MS": "5"}, "CHRONAV_ZENOH_LEASE_MS"),
    ({"CHRONAV_ZENOH_MTLS": "perhaps"}, "CHRONAV_ZENOH_MTLS"),
    ({"CHRONAV_ZENOH_USER": "a b", "CHRONAV_ZENOH_PASSWORD": "x"}, "CHRONAV_ZENOH_USER"),
    ({"CHRONAV_ZENOH_PASSWORD_FILE": "/nope"}, "CHRONAV_ZENOH_PASSWORD_FILE"),
])
def test_bad_settings_name_the_variable(env, var):
    with pytest.raises(ConfigError, match=var):
        ZenohSettings.from_env(env)


def test_pairs_are_checked(files):
    with pytest.raises(ValueError, match="go together"):
        ZenohSettings(tls_certificate=files["me.pem"])
    with pytest.raises(ValueError, match="mutual TLS"):
        ZenohSettings(mtls=True)
    with pytest.raises(ConfigError, match="not both"):
        ZenohSettings.from_env({"CHRONAV_ZENOH_PASSWORD": "a",
                                "CHRONAV_ZENOH_PASSWORD_FILE": str(files["password"])})


@pytest.mark.parametrize(("text", "where"), [
    ("robot:pw\njust-a-name\n", "creds.txt:2"),
    ("robot:\n", "creds.txt:1"),
    ("robot:a\nrobot:b\n", "creds.txt:2"),
    ("\n\n", "no 'user:password'"),
])
def test_credentials_file_errors_name_the_line(tmp_path, text, where):
    path = tmp_path / "creds.txt"
    path.write_text(text)
    with pytest.raises(ConfigError, match=where):
        check_credentials_file(path)


@pytest.mark.parametrize(("acl", "message"), [
    ('{access_control: {enabled: true, rules: [{id: "r", messages: ["putt"], flows: ["ingress"],'
     ' permission: "allow", key_exprs: ["a/**"]}]}}', "putt"),
    ('{access_control: {enabled: true, rules: [{id: "r", messages: ["put"], flows: ["ingress"],'
     ' permission: "allow", key_exprs: ["a/**"]}], subjects: [{id: "s", usernames: ["x"]}],'
     ' policies: [{rules: ["nope"], subjects: ["s"]}]}}', "unknown id 'nope'"),
    ("{access_control: {enabled: false}}", "enabled must be true"),
    ("{access_control: {enabled: true,", "invalid access-control file"),
])
def test_acl_file_errors_name_the_file(tmp_path, acl, message):
    path = tmp_path / "acl.json5"
    path.write_text(acl)
    with pytest.raises(ConfigError, match=message) as caught:
        load_acl(path)
    assert "acl.json5" in str(caught.value)


def test_shipped_deploy_files_are_valid():
    acl = load_acl(DEPLOY / "acl.json5")
    assert acl["default_permission"] == "deny"
    users = {line.split(":")[0] for line in (DEPLOY / "credentials.example.txt").read_text().split()}
    subjects = {u for s in acl["subjects"] for u in s["usernames"]}
    assert subjects == users
    check_credentials_file(DEPLOY / "credentials.example.txt")
    for name in ("robot", "camera", "server"):
        conf = ZenohSettings(config_file=DEPLOY / f"{name}.json5").to_zenoh_config()
        assert get(conf, "mode") == "client"
        assert get(conf, "scouting/multicast/enabled") is False
        assert get(conf, "connect/endpoints") == ["tls/10.0.0.1:7447"]
        assert get(conf, "transport/link/tls/root_ca_certificate") == "/etc/chronav/tls/ca.pem"
    conf = ZenohSettings(config_file=DEPLOY / "router.json5", mode="router").to_zenoh_config()
    assert get(conf, "listen/endpoints") == ["tls/10.0.0.1:7447"]
    assert get(conf, "transport/auth/usrpwd/dictionary_file") == "/etc/chronav/credentials.txt"


def test_router_settings_flags_over_env_and_file():
    env = {"CHRONAV_ZENOH_MODE": "client", "CHRONAV_ZENOH_CONNECT": "tcp/10.0.0.1:7447",
           "CHRONAV_ZENOH_ACL": str(DEPLOY / "acl.json5")}
    settings = router_settings(parse_args(["--listen", "tcp/127.0.0.1:9000",
                                           "--credentials", str(DEPLOY / "credentials.example.txt")]),
                               env)
    conf = settings.to_zenoh_config()
    assert get(conf, "mode") == "router"
    assert get(conf, "connect/endpoints") == []           # the agents' CONNECT is not for it
    assert get(conf, "listen/endpoints") == ["tcp/127.0.0.1:9000"]
    assert get(conf, "access_control/enabled") is True
    assert get(conf, "transport/auth/usrpwd/dictionary_file").endswith("credentials.example.txt")
    settings = router_settings(parse_args(["--config", str(DEPLOY / "router.json5"),
                                           "--lease-ms", "1000"]), {})
    conf = settings.to_zenoh_config()
    assert get(conf, "listen/endpoints") == ["tls/10.0.0.1:7447"]
    assert get(conf, "transport/link/tx/lease") == 1000
    assert router_settings(parse_args([]), {}).listen == ["tcp/127.0.0.1:7447"]
