"""A user file cannot pass for stvm's standard library (issue 34 item 7)."""

from __future__ import annotations

from pathlib import Path

import pytest

from stvm.cli import main
from stvm.source import SourceError, is_stdlib_file, read_source

NATIVE = """{native}
FUNCTION SHELL : INT
VAR_INPUT
    In : INT;
END_VAR
END_FUNCTION

PROGRAM Main
VAR x : INT; END_VAR
x := SHELL(1);
END_PROGRAM
"""


@pytest.mark.parametrize("name", ["<stdlib>x.st", "<stdlib>/bcd.st", "<builtin>"])
def test_a_file_named_like_the_stdlib_is_refused(tmp_path, monkeypatch, capsys, name: str) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
    (tmp_path / name).write_text(NATIVE, encoding="utf-8")
    assert main(["check", name]) == 1
    err = capsys.readouterr().err
    assert "keeps for its built-in sources" in err and "rename the file" in err
    assert "Traceback" not in err
    with pytest.raises(SourceError):
        read_source(Path(name))


def test_the_same_file_under_its_full_path_gets_no_stdlib_rights(tmp_path, capsys) -> None:
    path = tmp_path / "<stdlib>x.st"
    path.write_text(NATIVE, encoding="utf-8")
    assert main(["check", str(path)]) == 1
    assert "{native} is reserved for the stvm standard library" in capsys.readouterr().err


def test_stdlib_identity_is_the_exact_prefix() -> None:
    assert is_stdlib_file("<stdlib>/iec_functions.st")
    assert not is_stdlib_file("<stdlib>x.st")
    assert not is_stdlib_file("<stdlibx/a.st")
    assert not is_stdlib_file("/tmp/<stdlib>/a.st")
