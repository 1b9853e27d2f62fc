"""The compile cache cannot be poisoned (issue 17): entries are signed with a per-user key.

A crafted entry in the cache folder (a pickle that runs code when loaded) is never loaded;
a cache folder others can write, or a key file others can read, is refused with a warning.
"""

from __future__ import annotations

import os
import pickle
import warnings
from pathlib import Path

import pytest

import stvm
from stvm import project as project_module
from stvm.cache import CacheWarning, SignedCache, _WARNED

PROGRAM = "PROGRAM Main\nVAR x : INT; END_VAR\nx := x + 1;\nEND_PROGRAM\n"


class _Payload:
    """Unpickling this runs code: it creates the marker file."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (self.marker,))


@pytest.fixture
def private_cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    key = tmp_path / "config" / "cache.key"
    monkeypatch.setenv("STVM_CACHE_DIR", str(folder))
    monkeypatch.setenv("STVM_CACHE_KEY_FILE", str(key))
    monkeypatch.setattr(project_module, "_CACHES", {})
    _WARNED.clear()
    source = tmp_path / "main.st"
    source.write_text(PROGRAM)
    return folder, key, source


def test_a_second_load_comes_from_the_signed_cache(private_cache):
    folder, key, source = private_cache
    assert not stvm.load([source]).from_cache
    assert stvm.load([source]).from_cache
    assert key.stat().st_mode & 0o777 == 0o600
    assert folder.stat().st_mode & 0o077 == 0
    entries = list(folder.glob("*.bin"))
    assert entries and all(e.stat().st_mode & 0o077 == 0 for e in entries)


def test_a_forged_entry_is_never_unpickled(private_cache, tmp_path):
    folder, key, source = private_cache
    stvm.load([source])
    marker = tmp_path / "pwned"
    for entry in list(folder.glob("*.bin")) + list(folder.glob("stdlib-*.ast")):
        # what an attacker with write access to the folder can do: replace the entry, with or
        # without a plausible 32-byte prefix
        entry.write_bytes(pickle.dumps(_Payload(marker)))
    project_module._CACHES.clear()
    project = stvm.load([source])
    assert not marker.exists()
    assert not project.from_cache            # rebuilt
    entry = next(folder.glob("*.bin"))
    entry.write_bytes(b"\0" * 32 + pickle.dumps(_Payload(marker)))
    project_module._CACHES.clear()
    stvm.load([source])
    assert not marker.exists()


def test_an_entry_signed_with_another_key_is_rejected(tmp_path):
    ours = SignedCache(tmp_path / "c", tmp_path / "k1" / "key")
    ours.put("entry", b"payload")
    assert ours.get("entry") == b"payload"
    theirs = SignedCache(tmp_path / "c", tmp_path / "k2" / "key")
    assert theirs.get("entry") is None
    # a valid entry renamed to another name does not verify either
    os.replace(tmp_path / "c" / "entry", tmp_path / "c" / "other")
    assert ours.get("other") is None


def test_a_folder_writable_by_others_is_refused_with_a_warning(private_cache):
    folder, key, source = private_cache
    folder.mkdir(mode=0o700)
    folder.chmod(0o777)
    with pytest.warns(CacheWarning, match="writable by other users"):
        project = stvm.load([source])
    assert not project.from_cache
    assert not any(folder.iterdir())          # nothing written there
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert not stvm.load([source]).from_cache   # still not used; warned once per process


def test_a_key_others_can_read_disables_the_cache(private_cache):
    folder, key, source = private_cache
    key.parent.mkdir(parents=True)
    key.write_bytes(os.urandom(32))
    key.chmod(0o644)
    with pytest.warns(CacheWarning, match="mode 0600"):
        stvm.load([source])
    assert not folder.exists() or not any(folder.glob("*.bin"))


def test_the_cli_prints_one_warning_line(private_cache):
    from core_helpers import cli
    folder, key, source = private_cache
    folder.mkdir(mode=0o700)
    folder.chmod(0o757)
    rc, out, err = cli(["run", str(source), "--cycles", "1"])
    assert rc == 0
    assert err.count("stvm: warning: compile cache not used") == 1, err


def test_the_lint_parse_cache_never_unpickles_a_forged_entry(private_cache, tmp_path, monkeypatch):
    from stvm.lint import loader
    from stvm.settings import SysmacSettings
    folder, key, source = private_cache
    monkeypatch.setattr(loader, "_CACHES", {})
    monkeypatch.setattr(loader, "_MEMO", {})
    settings = SysmacSettings()
    loader.parse_cached(PROGRAM, "main.st", settings)
    entries = list((folder / "lint-ast").glob("*.pickle"))
    assert entries and all(e.stat().st_mode & 0o077 == 0 for e in entries)
    loader._MEMO.clear()
    unit, _ = loader.parse_cached(PROGRAM, "main.st", settings)     # from the signed entry
    assert unit is not None
    marker = tmp_path / "pwned"
    for entry in entries:
        entry.write_bytes(pickle.dumps(_Payload(marker)))
    loader._MEMO.clear()
    unit, _ = loader.parse_cached(PROGRAM, "main.st", settings)
    assert not marker.exists() and unit is not None               # parsed again, nothing ran
