"""`--opcua` URLs and the manifest's [opcua] table: every mistake is a clear error."""

import hashlib
from pathlib import Path

import pytest

from stvm.opcua.config import OpcUaConfigError, is_loopback, load_config, parse_endpoint


def config(table=None, url=None, root=None, **manifest):
    return load_config({"opcua": table or {}, **manifest}, root, ["main.st"], url)


@pytest.mark.parametrize("url, host, port", [
    ("opc.tcp://127.0.0.1:4840", "127.0.0.1", 4840),
    ("opc.tcp://localhost:0/stvm", "localhost", 0),
    ("opc.tcp://[::1]:4841", "::1", 4841),
    ("opc.tcp://plc.example.com:4840", "plc.example.com", 4840),
    ("127.0.0.1:4850", "127.0.0.1", 4850),            # HOST:PORT for short, as --hmi takes it
    ("[::1]:4851", "::1", 4851),
])
def test_endpoints(url, host, port):
    endpoint = parse_endpoint(url)
    assert (endpoint.host, endpoint.port) == (host, port)


@pytest.mark.parametrize("url", ["127.0.0.1", "127.0.0.1:", "http://127.0.0.1:4840", "opc.tcp://127.0.0.1",
                                 "opc.tcp://127.0.0.1:99999", "opc.tcp://user:pw@127.0.0.1:4840",
                                 "opc.tcp://bad_host!:4840", "opc.tcp://:4840"])
def test_bad_endpoints_are_usage_errors(url):
    with pytest.raises(OpcUaConfigError, match="opc.tcp://HOST:PORT|users"):
        parse_endpoint(url)


def test_loopback_addresses():
    assert is_loopback("127.0.0.1") and is_loopback("127.5.0.1") and is_loopback("::1") and is_loopback("LOCALHOST")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.168.0.10") and not is_loopback("plc.local")


def test_defaults_and_namespace():
    cfg = config(project={"name": "Cell 7"})
    assert cfg.endpoint.url == "opc.tcp://127.0.0.1:4840"
    assert cfg.publish == ("@globals", "@programs") and cfg.writable == ("@globals", "@program_inputs")
    assert cfg.namespace_uri == "urn:stvm:Cell_7" and not cfg.start_paused
    assert config(url="opc.tcp://127.0.0.1:0").endpoint.port == 0          # the command line wins
    assert config(root=Path("/x/st_src")).namespace_uri == "urn:stvm:st_src"


@pytest.mark.parametrize("table, message", [
    ({"publsh": []}, "unknown key.*publsh"),
    ({"publish": "@globals"}, "publish: expected a list of strings"),
    ({"writable": ["@everything"]}, "unknown set '@everything'"),
    ({"start": "stopped"}, "start: expected \"running\" or \"paused\""),
    ({"endpoint": "tcp://x"}, "endpoint: expected opc.tcp://"),
    ({"users": {"op": "secret"}}, "users.op: expected \"env:VAR\""),
    ({"users": {"op": "env:STVM_TEST_UNSET_VARIABLE"}}, "not set"),
    ({"certificate": "missing.der", "private_key": "missing.pem"}, "no such file"),
])
def test_bad_tables_name_the_entry(table, message):
    with pytest.raises(OpcUaConfigError, match=message):
        config(table)


def test_users_from_environment_and_digest(monkeypatch):
    monkeypatch.setenv("STVM_TEST_PW", "s3cret")
    digest = hashlib.sha256(b"other").hexdigest()
    cfg = config({"users": {"op": "env:STVM_TEST_PW", "eng": f"sha256:{digest.upper()}"}})
    assert cfg.users == {"op": hashlib.sha256(b"s3cret").hexdigest(), "eng": digest}


def test_non_loopback_needs_certificate_and_authentication(tmp_path, monkeypatch):
    with pytest.raises(OpcUaConfigError, match="not a loopback address: anonymous and unencrypted"):
        config(url="opc.tcp://0.0.0.0:4840")
    (tmp_path / "c.der").write_bytes(b"x")
    (tmp_path / "k.pem").write_bytes(b"x")
    secure = {"certificate": "c.der", "private_key": "k.pem"}
    with pytest.raises(OpcUaConfigError, match="clients must authenticate"):
        config(secure, url="opc.tcp://192.168.0.10:4840", root=tmp_path)
    with pytest.raises(OpcUaConfigError, match="go together"):
        config({"certificate": "c.der"}, root=tmp_path)
    monkeypatch.setenv("STVM_TEST_PW", "pw")
    cfg = config({**secure, "users": {"op": "env:STVM_TEST_PW"}}, url="opc.tcp://192.168.0.10:4840", root=tmp_path)
    assert cfg.secure and not cfg.endpoint.loopback
