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


def test_lint_reads_the_drivers_signed_unit_entries_and_never_a_forged_one(private_cache, tmp_path):
    """`stvm lint` parses through the project driver: its trees are the driver's signed
    `unit-*.ast` entries, so a forged entry is parsed again, never unpickled."""
    from stvm.lint import lint
    folder, key, source = private_cache
    report = lint([source])
    entries = list(folder.glob("unit-*.ast"))
    assert entries and all(e.stat().st_mode & 0o077 == 0 for e in entries)
    assert not report.has_errors and report.files == [str(source)]
    marker = tmp_path / "pwned"
    for entry in entries:
        entry.write_bytes(b"\0" * 32 + pickle.dumps(_Payload(marker)))
    project_module._CACHES.clear()
    report = lint([source])
    assert not marker.exists() and not report.has_errors      # parsed again, nothing ran


# ---- the parse and check caches (issue 16): an unchanged project skips parse and check

OTHER = "FUNCTION Twice : INT\nVAR_INPUT v : INT; END_VAR\nTwice := v * 2;\nEND_FUNCTION\n"


def _counting_parser(monkeypatch):
    """Count the user files the parser really parses (the stdlib is memoised in-process)."""
    from stvm.syntax import parser
    parsed: list[str] = []
    real = parser.parse_text

    def counting(text, name, *args, **kwargs):
        if not name.startswith("<stdlib>"):
            parsed.append(name)
        return real(text, name, *args, **kwargs)
    monkeypatch.setattr(parser, "parse_text", counting)
    return parsed


def test_an_unchanged_project_is_checked_from_the_cache(private_cache, tmp_path, monkeypatch):
    folder, key, source = private_cache
    other = tmp_path / "lib.st"
    other.write_text(OTHER)
    parsed = _counting_parser(monkeypatch)
    analysis, diags, _ = project_module.check([source, other], generate=True)
    assert analysis is not None and not diags and sorted(parsed) == sorted([str(source), str(other)])
    parsed.clear()
    import stvm.semantics.checker as checker
    monkeypatch.setattr(checker, "analyze", lambda *a, **k: pytest.fail("checked again"))
    analysis, diags, sources = project_module.check([source, other], generate=True)
    assert not parsed and not diags and str(source) in sources
    assert list(folder.glob("check-*.diag")) and len(list(folder.glob("unit-*.ast"))) == 2
    monkeypatch.undo()
    # the analysis of a cached verdict is still there for a caller that reads it
    assert "main" in {k.split("\\")[-1] for k in analysis.model.pous}


def test_an_edit_reparses_only_the_file_edited_and_the_verdict_follows(private_cache, tmp_path, monkeypatch):
    folder, key, source = private_cache
    other = tmp_path / "lib.st"
    other.write_text(OTHER)
    assert not project_module.check([source, other])[1]
    parsed = _counting_parser(monkeypatch)
    source.write_text(PROGRAM.replace("x + 1", "x + y"))
    analysis, diags, sources = project_module.check([source, other])
    assert parsed == [str(source)]                      # lib.st came from the unit cache
    assert analysis is None and [d.message for d in diags] == ["'y' is not declared"]
    parsed.clear()
    again = project_module.check([source, other])       # the error verdict is cached too
    assert not parsed and again[0] is None and [d.message for d in again[1]] == ["'y' is not declared"]
    assert "x + y" in again[2][str(source)]


def test_a_one_file_load_writes_no_unit_entry_a_project_one_per_file(private_cache, tmp_path, monkeypatch):
    """A one-file project's unit entry could only spare a later `stvm check` its parse (an edit
    makes it stale with the load entry), so its first load does not pickle it; a project's
    files keep theirs (an edit re-parses only the file edited)."""
    folder, key, source = private_cache
    stvm.load([source])
    assert list(folder.glob("*.bin")) and not list(folder.glob("unit-*.ast"))
    other = tmp_path / "lib.st"
    other.write_text(OTHER)
    stvm.load([source, other])
    assert len(list(folder.glob("unit-*.ast"))) == 2
    parsed = _counting_parser(monkeypatch)
    other.write_text(OTHER + "\n")
    assert not stvm.load([source, other]).from_cache and parsed == [str(other)]


def test_other_settings_are_another_cache_entry(private_cache, monkeypatch):
    from stvm.settings import DEFAULT_SETTINGS
    folder, key, source = private_cache
    project_module.check([source])
    parsed = _counting_parser(monkeypatch)
    other = DEFAULT_SETTINGS.with_overrides(["int_div_zero=zero"])
    assert other != DEFAULT_SETTINGS
    project_module.check([source], other)
    assert parsed == [str(source)]
    assert len(list(folder.glob("check-*.diag"))) == 2


def test_forged_check_and_unit_entries_are_never_unpickled(private_cache, tmp_path):
    folder, key, source = private_cache
    project_module.check([source], generate=True)
    marker = tmp_path / "pwned"
    entries = list(folder.glob("check-*.diag")) + list(folder.glob("unit-*.ast"))
    assert len(entries) == 2
    for entry in entries:
        entry.write_bytes(b"\0" * 32 + pickle.dumps(_Payload(marker)))
    project_module._CACHES.clear()
    analysis, diags, _ = project_module.check([source], generate=True)
    assert not marker.exists() and analysis is not None and not diags


def test_native_name_pattern_matches_whole_generated_names_only():
    """project._NATIVE_NAME (a cached load imports the modules of the natives it finds) finds
    what `\\bN[0-9]+_\\w+` finds, on names inside words, at the start and glued to digits."""
    import re

    from stvm.project import _NATIVE_NAME
    text = "N1_abs(x) + xN2_no + _N3_no + (N44_max_2) N5_ 9N6_no N7_x\nN8_y.N9_z"
    assert _NATIVE_NAME.findall(text) == re.findall(r"\bN[0-9]+_\w+", text)
    assert _NATIVE_NAME.findall(text) == ["N1_abs", "N44_max_2", "N7_x", "N8_y", "N9_z"]
