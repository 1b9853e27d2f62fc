"""Cache entries that are not regular files, and Lark's own unsigned cache (issues 34 item 8,
28.4): a symbolic link to /dev/zero, a FIFO, a folder or an oversized file under an entry's name
is treated as a missing entry; the parser tables are cached signed, never by Lark's `cache=`."""

from __future__ import annotations

import os
import pickle
import threading
from pathlib import Path

import pytest

from stvm.cache import SignedCache, _WARNED, read_regular_file
from stvm.syntax import parser as parser_module
from stvm.syntax import tables


@pytest.fixture
def cache(tmp_path, monkeypatch) -> SignedCache:
    monkeypatch.setenv("STVM_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("STVM_CACHE_KEY_FILE", str(tmp_path / "config" / "cache.key"))
    _WARNED.clear()
    c = SignedCache()
    c.put("seed.bin", b"x")   # creates the folder and the key
    assert c.get("seed.bin") == b"x"
    return c


def _in_thread(fn, timeout_s: float = 5.0):
    """Run fn in a thread; a hang fails the test instead of the whole session."""
    result: list = []
    t = threading.Thread(target=lambda: result.append(fn()), daemon=True)
    t.start()
    t.join(timeout_s)
    assert not t.is_alive(), "the cache read hangs"
    return result[0]


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_symlink_to_dev_zero_is_a_miss(cache) -> None:
    os.symlink("/dev/zero", cache.path("entry.bin"))
    assert _in_thread(lambda: cache.get("entry.bin")) is None


def test_fifo_is_a_miss_and_does_not_hang(cache) -> None:
    os.mkfifo(cache.path("entry.bin"))
    assert _in_thread(lambda: cache.get("entry.bin")) is None


def test_folder_is_a_miss_and_leaves_no_temporary_file(cache) -> None:
    cache.path("entry.bin").mkdir()
    assert cache.get("entry.bin") is None
    for _ in range(3):
        cache.put("entry.bin", b"payload")
    assert sorted(p.name for p in cache.folder.iterdir()) == ["entry.bin", "seed.bin"]


def test_symlink_to_a_signed_entry_is_not_followed(cache) -> None:
    cache.put("real.bin", b"payload")
    os.symlink(cache.path("real.bin"), cache.path("alias.bin"))
    assert cache.get("alias.bin") is None


def test_oversized_entry_is_a_miss(cache, monkeypatch) -> None:
    cache.put("big.bin", b"y" * (2 * 2**20))
    assert cache.get("big.bin") == b"y" * (2 * 2**20)
    monkeypatch.setenv("STVM_CACHE_MAX_ENTRY_MB", "1")
    assert cache.get("big.bin") is None


def test_read_regular_file_reads_a_file_whole(tmp_path) -> None:
    f = tmp_path / "f"
    f.write_bytes(b"abc" * 100_000)
    assert read_regular_file(f, 1 << 20) == b"abc" * 100_000
    assert read_regular_file(f, 10) is None
    assert read_regular_file(tmp_path, 1 << 20) is None


class _Payload:
    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (self.marker,))


def test_parser_tables_are_cached_signed_never_by_lark(cache, monkeypatch, tmp_path) -> None:
    """As on Python >= 3.12 (shipped tables not usable): the tables Lark builds go into the
    signed cache; a pickle planted under their name is never loaded."""
    monkeypatch.setattr(tables, "load", lambda grammar, options: None)
    calls: list[dict] = []
    real_lark = parser_module.Lark

    def lark(*args, **kwargs):
        calls.append(kwargs)
        return real_lark(*args, **kwargs)

    monkeypatch.setattr(parser_module, "Lark", lark)
    parser_module._parser.cache_clear()
    try:
        built = parser_module._parser()
        entries = [p for p in cache.folder.iterdir() if p.name.startswith("lark-tables-")]
        assert len(entries) == 1
        # the entry is signed: its payload is Lark's save() format behind a 32-byte tag
        name = entries[0].name
        assert cache.get(name) is not None
        # a planted pickle under the same name: not loaded, the tables are rebuilt
        marker = tmp_path / "pwned"
        entries[0].write_bytes(pickle.dumps(_Payload(marker)))
        parser_module._parser.cache_clear()
        rebuilt = parser_module._parser()
        assert not marker.exists()
        assert rebuilt is not built
        assert cache.get(name) is not None   # rebuilt and signed again
        # Lark itself was never given a cache file
        assert all("cache" not in kwargs for kwargs in calls)
    finally:
        parser_module._parser.cache_clear()
