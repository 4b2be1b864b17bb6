"""Zenoh settings from the environment, and the hybrid logical clock."""

from __future__ import annotations

import json

import pytest

from dsr import ConfigError, ZenohSettings, graph_name_from_env
from dsr.hlc import MAX_OFFSET_MS, HybridLogicalClock, pack, wall_ms


def get(conf, key):
    return json.loads(conf.get_json(key))


def test_defaults_are_loopback_client_without_multicast():
    settings = ZenohSettings.from_env({})
    assert settings.mode == "client" and settings.connect == ["tcp/127.0.0.1:7447"]
    conf = settings.to_zenoh_config()
    assert get(conf, "scouting/multicast/enabled") is False
    assert get(conf, "connect/endpoints") == ["tcp/127.0.0.1:7447"]
    assert get(conf, "listen/endpoints") == []
    assert get(conf, "mode") == "client"
    assert get(conf, "transport/shared_memory/enabled") is False   # tests/integration/test_zenoh_shared_memory.py


def test_shared_memory_follows_the_variable_and_a_config_file(tmp_path):
    on = ZenohSettings.from_env({"CHRONAV_ZENOH_SHARED_MEMORY": "1"}).to_zenoh_config()
    assert get(on, "transport/shared_memory/enabled") is True
    path = tmp_path / "z.json5"
    path.write_text("{transport: {shared_memory: {enabled: true}}}")
    assert get(ZenohSettings(config_file=path).to_zenoh_config(), "transport/shared_memory/enabled") is True
    off = ZenohSettings.from_env({"CHRONAV_ZENOH_CONFIG": str(path), "CHRONAV_ZENOH_SHARED_MEMORY": "off"})
    assert get(off.to_zenoh_config(), "transport/shared_memory/enabled") is False


def test_environment_overrides():
    env = {"CHRONAV_ZENOH_CONNECT": "tcp/10.0.0.2:7447, tcp/10.0.0.3:7447",
           "CHRONAV_ZENOH_LISTEN": "tcp/0.0.0.0:7448", "CHRONAV_ZENOH_MODE": "peer"}
    conf = ZenohSettings.from_env(env).to_zenoh_config()
    assert get(conf, "connect/endpoints") == ["tcp/10.0.0.2:7447", "tcp/10.0.0.3:7447"]
    assert get(conf, "listen/endpoints") == ["tcp/0.0.0.0:7448"]
    assert get(conf, "mode") == "peer"


def test_router_listens_on_loopback_by_default():
    conf = ZenohSettings(mode="router", listen=[]).to_zenoh_config()
    assert get(conf, "listen/endpoints") == ["tcp/127.0.0.1:7447"]
    assert get(conf, "connect/endpoints") == []


@pytest.mark.parametrize(("env", "var"), [
    ({"CHRONAV_ZENOH_MODE": "server"}, "CHRONAV_ZENOH_MODE"),
    ({"CHRONAV_ZENOH_CONNECT": "127.0.0.1:7447"}, "CHRONAV_ZENOH_CONNECT"),
    ({"CHRONAV_ZENOH_CONFIG": "/nonexistent.json5"}, "CHRONAV_ZENOH_CONFIG"),
    ({"CHRONAV_ZENOH_MULTICAST": "maybe"}, "CHRONAV_ZENOH_MULTICAST"),
    ({"CHRONAV_ZENOH_SHARED_MEMORY": "sometimes"}, "CHRONAV_ZENOH_SHARED_MEMORY"),
])
def test_bad_environment_names_the_variable(env, var):
    with pytest.raises(ConfigError, match=var):
        ZenohSettings.from_env(env)


def test_config_file_is_base_and_env_overrides(tmp_path):
    path = tmp_path / "z.json5"
    path.write_text('{mode: "peer", connect: {endpoints: ["tcp/127.0.0.1:9999"]},'
                    ' listen: {endpoints: ["tcp/127.0.0.1:9998"]}}')
    conf = ZenohSettings.from_env({"CHRONAV_ZENOH_CONFIG": str(path)}).to_zenoh_config()
    assert get(conf, "mode") == "peer"
    assert get(conf, "connect/endpoints") == ["tcp/127.0.0.1:9999"]
    assert get(conf, "scouting/multicast/enabled") is False
    conf = ZenohSettings.from_env({"CHRONAV_ZENOH_CONFIG": str(path),
                                   "CHRONAV_ZENOH_CONNECT": "tcp/127.0.0.1:1234"}
                                  ).to_zenoh_config()
    assert get(conf, "connect/endpoints") == ["tcp/127.0.0.1:1234"]
    assert get(conf, "listen/endpoints") == ["tcp/127.0.0.1:9998"]
    path.write_text("{mode: ")
    with pytest.raises(ConfigError, match="z.json5"):
        ZenohSettings(config_file=path).to_zenoh_config()


def test_graph_name():
    assert graph_name_from_env({}) == "chronav"
    assert graph_name_from_env({"CHRONAV_GRAPH": "ward2"}) == "ward2"
    with pytest.raises(ConfigError, match="CHRONAV_GRAPH"):
        graph_name_from_env({"CHRONAV_GRAPH": "a/b"})


def test_hlc_is_monotonic_and_follows_remote_clocks():
    now = [1000]
    clock = HybridLogicalClock(now_ms=lambda: now[0])
    first = clock.tick()
    assert first == pack(1000) and clock.tick() == pack(1000, 1)
    now[0] = 900                                 # wall clock went backwards
    assert clock.tick() == pack(1000, 2)
    clock.observe(pack(5000, 7))                 # a remote write we have seen
    assert clock.tick() == pack(5000, 8)
    now[0] = 6000
    assert clock.tick() == pack(6000) and wall_ms(clock.last) == 6000
    assert clock.too_far_ahead(pack(6000 + MAX_OFFSET_MS + 1))
    assert not clock.too_far_ahead(pack(6000 + MAX_OFFSET_MS - 1))
