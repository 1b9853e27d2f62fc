"""The standard address space comes from stvm's signed cache only (issue 34 item 1): a planted
shelf or entry never runs its pickle payload, a forged or damaged entry is rebuilt, a folder
others can write is refused, new folders are private."""

from __future__ import annotations

import asyncio
import hashlib
import hmac
import os
import pickle
import shelve
import shutil
import stat
from pathlib import Path

import asyncua
import pytest
from asyncua import Client, Server, ua

from opcua_helpers import Running, run_async
from stvm.cache import TAG_BYTES, SignedCache
from stvm.opcua import aspace_cache
from stvm.opcua.aspace_cache import decode, encode, entry_name, init_server

pytestmark = pytest.mark.filterwarnings("ignore::stvm.cache.CacheWarning")


class _Payload:
    """Unpickling this creates the marker file: proof that bytes were unpickled."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return open, (str(self.marker), "w")


def _evil_records(marker: Path) -> dict[str, bytes]:
    evil = pickle.dumps(_Payload(marker), pickle.HIGHEST_PROTOCOL)
    # every node asyncua asks for first, and the probe, carry the payload
    return {ua.NodeId(i).to_string(): evil for i in (ua.ObjectIds.RootFolder, ua.ObjectIds.Server,
                                                     ua.ObjectIds.ObjectsFolder, ua.ObjectIds.Server_NamespaceArray)}


def _tag(key: bytes, name: str, payload: bytes) -> bytes:
    return hmac.new(key, name.encode() + b"\0" + payload, hashlib.sha256).digest()


def _init(server: Server | None = None) -> tuple[str, Server]:
    server = server or Server()

    async def go():
        return await init_server(server)
    return asyncio.run(go()), server


@pytest.fixture(scope="module")
def valid_entry(tmp_path_factory) -> bytes:
    """One entry built and signed with the suite's key (built once, copied into each test's folder)."""
    folder = tmp_path_factory.mktemp("built") / "cache"
    old = os.environ.get("STVM_CACHE_DIR")
    os.environ["STVM_CACHE_DIR"] = str(folder)
    try:
        how, _ = _init()
    finally:
        if old is None:
            del os.environ["STVM_CACHE_DIR"]
        else:
            os.environ["STVM_CACHE_DIR"] = old
    assert how == "built and cached"
    return (folder / entry_name()).read_bytes()


@pytest.fixture
def cache_dir(tmp_path, monkeypatch) -> Path:
    folder = tmp_path / "cache"
    monkeypatch.setenv("STVM_CACHE_DIR", str(folder))
    return folder


def test_the_payload_of_the_tests_is_live(tmp_path):
    # the planted bytes below really run code when unpickled: the tests that follow mean something
    marker = tmp_path / "ran"
    pickle.loads(next(iter(_evil_records(marker).values())))
    assert marker.exists()


def test_a_planted_asyncua_shelf_is_never_opened(cache_dir, tmp_path, valid_entry):
    # what stvm used to open: $STVM_CACHE_DIR/asyncua-<ver>-aspace/aspace (a dbm.dumb shelf)
    marker = tmp_path / "ran"
    folder = cache_dir / f"asyncua-{asyncua.__version__}-aspace"
    folder.mkdir(parents=True, mode=0o700)
    import dbm.dumb
    with shelve.Shelf(dbm.dumb.open(str(folder / "aspace"), "n")) as shelf:
        for key in _evil_records(marker):
            shelf[key] = _Payload(marker)
    (folder / "aspace").touch()
    (cache_dir / entry_name()).write_bytes(valid_entry)
    how, server = _init()
    assert how == "cache"
    assert not marker.exists()
    assert server.iserver.aspace[ua.NodeId(ua.ObjectIds.RootFolder)].nodeid == ua.NodeId(ua.ObjectIds.RootFolder)


@pytest.mark.parametrize("signer", ["unsigned", "another key"])
def test_a_planted_entry_is_rebuilt_without_running_it(cache_dir, tmp_path, signer):
    marker = tmp_path / "ran"
    payload = encode(_evil_records(marker))
    tag = b"\0" * TAG_BYTES if signer == "unsigned" else _tag(b"k" * 32, entry_name(), payload)
    cache_dir.mkdir(mode=0o700)
    (cache_dir / entry_name()).write_bytes(tag + payload)
    how, server = _init()
    assert how == "built and cached"
    assert not marker.exists()
    rebuilt = SignedCache(cache_dir).get(entry_name())
    assert rebuilt is not None and str(marker).encode() not in rebuilt
    assert len(decode(rebuilt)) > 5000
    how, _ = _init()
    assert how == "cache" and not marker.exists()


@pytest.mark.parametrize("damage", ["truncated", "not records"])
def test_a_damaged_entry_is_rebuilt(cache_dir, valid_entry, damage):
    cache_dir.mkdir(mode=0o700)
    if damage == "truncated":   # the tag no longer verifies (as for any changed byte)
        data = valid_entry[:len(valid_entry) // 2]
    else:   # signed by us, but not in the record format: still rebuilt, nothing unpickled
        key = SignedCache(cache_dir)
        key._ready()
        junk = aspace_cache.MAGIC + b"\0\0\0\x09short"
        data = key._tag(entry_name(), junk) + junk
    (cache_dir / entry_name()).write_bytes(data)
    how, server = _init()
    assert how == "built and cached"
    assert SignedCache(cache_dir).get(entry_name()) is not None
    assert ua.NodeId(ua.ObjectIds.Server) in server.iserver.aspace


def test_a_folder_others_can_write_is_refused(cache_dir, tmp_path, valid_entry):
    marker = tmp_path / "ran"
    cache_dir.mkdir()
    os.chmod(cache_dir, 0o777)
    # even an entry that verifies is not read from a folder others could have written
    key = SignedCache(tmp_path / "private")
    key._ready()
    payload = encode(_evil_records(marker))
    (cache_dir / entry_name()).write_bytes(key._tag(entry_name(), payload) + payload)
    before = (cache_dir / entry_name()).read_bytes()
    how, server = _init()
    assert how == "built"
    assert not marker.exists()
    assert (cache_dir / entry_name()).read_bytes() == before     # nothing written there either
    assert sorted(p.name for p in cache_dir.iterdir()) == [entry_name()]
    assert ua.NodeId(ua.ObjectIds.Server) in server.iserver.aspace


def test_a_new_cache_folder_is_private(tmp_path, monkeypatch, valid_entry):
    folder = tmp_path / "new" / "stvm"
    monkeypatch.setenv("STVM_CACHE_DIR", str(folder))
    how, _ = _init()
    assert how == "built and cached"
    assert stat.S_IMODE(folder.stat().st_mode) == 0o700
    assert stat.S_IMODE((folder / entry_name()).stat().st_mode) == 0o600


def test_decode_refuses_what_is_not_the_record_format():
    good = encode({"i=1": b"a", "ns=2;s=x": b"bc"})
    assert decode(good) == {b"i=1": b"a", b"ns=2;s=x": b"bc"}
    assert decode(good[:-1]) is None                     # a value cut short
    assert decode(good + b"x") is None                   # trailing bytes
    assert decode(b"x" + good[1:]) is None               # wrong magic
    assert decode(good[:len(aspace_cache.MAGIC)] + b"\xff\xff\xff\xff") is None   # a count without records


def test_the_server_serves_with_a_planted_shelf_in_the_cache(cache_dir, tmp_path, thesis_project, valid_entry):
    marker = tmp_path / "ran"
    folder = cache_dir / f"asyncua-{asyncua.__version__}-aspace"
    folder.mkdir(parents=True, mode=0o700)
    import dbm.dumb
    with shelve.Shelf(dbm.dumb.open(str(folder / "aspace"), "n")) as shelf:
        for key in _evil_records(marker):
            shelf[key] = _Payload(marker)
    (folder / "aspace").touch()
    shutil.copy(folder / "aspace.dat", folder / "aspace.db")
    run = Running(thesis_project)
    try:
        async def client():
            async with Client(run.url) as c:
                state = await c.get_node(ua.ObjectIds.Server_ServerStatus_State).read_value()
                ns = await c.get_namespace_array()
                return state, ns
        state, ns = run_async(client())
    finally:
        run.close()
    assert state == ua.ServerState.Running
    assert run.ns_uri in ns
    assert not marker.exists()
    assert SignedCache(cache_dir).get(entry_name()) is not None
