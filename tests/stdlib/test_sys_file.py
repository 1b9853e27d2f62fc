"""SysFile / SysDir under `--dialect twincat` (stvm/stdlib/sys_file.*): real files, confined to
the run's file root (`--files-root`, `[files] root`)."""

from __future__ import annotations

import os

import pytest

from stvm.manifest import ManifestError, check_manifest
from stvm.settings import SysmacSettings
from stvm.stdlib.sys_file import (AM_APPEND, AM_READ, AM_WRITE, ERR_NO_ACCESS_RIGHTS, ERR_NO_OBJECT, ERR_OK,
                                  INVALID_HANDLE, AccessRefused, FileRoot, default_root)
from tests.core_helpers import cli, load_st, write_files

TWINCAT = SysmacSettings(dialect="twincat")

PROGRAM = """
PROGRAM Main
VAR
  h : SysFile.SysTypes.RTS_IEC_HANDLE;
  opened, wrote, dir, outside : SysFile.SysTypes.RTS_IEC_RESULT;
  deleted, missing : SysFile.SysTypes.RTS_IEC_RESULT;
  buf : ARRAY[0..15] OF BYTE;
  back : ARRAY[0..15] OF BYTE;
  n, m : __UXINT;
  invalid : BOOL;
END_VAR
buf[0] := 72; buf[1] := 105; buf[2] := 10;
dir := SysDir.SysDirCreate('%TC_BOOTPRJPATH%out');
h := SysFile.SysFileOpen(szFile := '%TC_BOOTPRJPATH%out/result.xml', am := SysFile.AM_WRITE_PLUS,
                         pResult := ADR(opened));
n := SysFile.SysFileWrite(hFile := h, pbyBuffer := ADR(buf[0]), ulSize := 3, pResult := ADR(wrote));
SysFile.SysFileClose(h);
h := SysFile.SysFileOpen(szFile := 'out\\result.xml', am := SysFile.ACCESS_MODE.AM_READ, pResult := ADR(opened));
m := SysFile.SysFileRead(hFile := h, pbyBuffer := ADR(back[0]), ulSize := 16, pResult := ADR(wrote));
SysFile.SysFileClose(h);
h := SysFile.SysFileOpen(szFile := '../escape.txt', am := SysFile.AM_WRITE, pResult := ADR(outside));
invalid := h = SysFile.SysTypes.RTS_INVALID_HANDLE;
deleted := SysFile.SysFileDelete('out/result.xml');
missing := SysFile.SysFileDelete('out/result.xml');
END_PROGRAM
"""


def test_write_read_delete_in_the_file_root(tmp_path):
    project = load_st(PROGRAM, settings=TWINCAT)
    project.files_root = str(tmp_path / "files")
    vm = project.start()
    vm.run(cycles=1)
    assert vm["Main.dir"] == ERR_OK and vm["Main.opened"] == ERR_OK
    assert (vm["Main.n"], vm["Main.m"]) == (3, 3)
    assert vm["Main.back[0]"] == 72 and vm["Main.back[2]"] == 10
    assert vm["Main.outside"] == ERR_NO_ACCESS_RIGHTS and vm["Main.invalid"]
    assert (vm["Main.deleted"], vm["Main.missing"]) == (ERR_OK, ERR_NO_OBJECT)
    assert (tmp_path / "files" / "out").is_dir() and not (tmp_path / "escape.txt").exists()


def test_the_command_line_names_the_root(tmp_path):
    src = PROGRAM.replace("deleted := SysFile.SysFileDelete('out/result.xml');", "")
    src = src.replace("missing := SysFile.SysFileDelete('out/result.xml');", "")
    (path,) = write_files({"main.st": src})
    rc, out, err = cli(["run", "--dialect", "twincat", str(path), "--files-root", str(tmp_path / "r"),
                        "--cycles", "1", "--print", "Main.n"])
    assert rc == 0, err
    assert (tmp_path / "r" / "out" / "result.xml").read_bytes() == b"Hi\n"


def test_names_outside_the_root_are_refused(tmp_path):
    files = FileRoot(tmp_path / "root")
    (tmp_path / "root").mkdir()
    (tmp_path / "secret.txt").write_text("x")
    os.symlink(tmp_path, tmp_path / "root" / "up")
    outside = str(tmp_path / "secret.txt").encode()
    for name in (b"../secret.txt", b"a/../../secret.txt", b"up/secret.txt", b"", b"%TC_BOOTPRJPATH%",
                 outside, b"/etc/passwd", b"C:\\TwinCAT\\3.1\\Boot\\x.txt", b"x/%TC_BOOTPRJPATH%y"):
        with pytest.raises(AccessRefused):
            files.path(name)
    assert files.open(b"up/secret.txt", AM_READ) == (INVALID_HANDLE, ERR_NO_ACCESS_RIGHTS)
    # the placeholders stand for the root; an absolute path inside the root is allowed
    for name in (b"%TC_TARGETPATH%x.txt", b"%TC_BOOTPRJPATH%\\sub\\x.txt", str(tmp_path / "root" / "x.txt").encode()):
        inside = files.path(name)
        assert (tmp_path / "root") in inside.parents


def test_open_modes(tmp_path):
    files = FileRoot(tmp_path)
    assert files.open(b"none.txt", AM_READ)[1] == ERR_NO_OBJECT
    assert files.open(b"none.txt", AM_APPEND)[1] == ERR_NO_OBJECT
    handle, error = files.open(b"new.txt", AM_WRITE)
    assert error == ERR_OK and handle == 1 and (tmp_path / "new.txt").exists()
    files.close_all()


def test_the_manifest_names_the_root(tmp_path):
    assert default_root({"files": {"root": "plc"}}, tmp_path) == tmp_path / "plc"
    assert default_root({"project": {}}, tmp_path) == tmp_path / "stvm_files"
    assert default_root({}, None) is None        # a temporary folder of the run
    assert check_manifest({"files": {"root": "plc"}}, "stvm.toml")
    with pytest.raises(ManifestError, match=r"\[files\]: unknown key"):
        check_manifest({"files": {"folder": "plc"}}, "stvm.toml")


def test_tc2_system_file_function_blocks(tmp_path):
    src = """
PROGRAM Main
VAR op : FB_FileOpen; cl : FB_FileClose; del : FB_FileDelete; step : INT; h : UINT;
    openErr, closeErr, delErr, badErr : BOOL; delId : UDINT; END_VAR
CASE step OF
0: op(sPathName := 'log/a.txt', nMode := FOPEN_MODEWRITE OR FOPEN_MODETEXT, bExecute := TRUE);
   IF NOT op.bBusy THEN h := op.hFile; openErr := op.bError; step := 1; END_IF
1: cl(hFile := h, bExecute := TRUE); closeErr := cl.bError; step := 2;
2: del(sPathName := 'log/missing.txt', bExecute := TRUE); delErr := del.bError; delId := del.nErrId; step := 3;
3: op(bExecute := FALSE); step := 4;
4: op(sPathName := '../a.txt', nMode := FOPEN_MODEREAD, bExecute := TRUE); badErr := op.bError; step := 5;
END_CASE
END_PROGRAM
"""
    (tmp_path / "log").mkdir()
    project = load_st(src, settings=TWINCAT)
    project.files_root = str(tmp_path)
    vm = project.start()
    vm.run(cycles=6)
    assert (vm["Main.h"], vm["Main.openErr"], vm["Main.closeErr"]) == (1, False, False)
    assert (tmp_path / "log" / "a.txt").is_file()
    assert (vm["Main.delErr"], vm["Main.delId"]) == (True, 0x70C)     # ADS: not found
    assert vm["Main.badErr"] and vm["Main.op.nErrId"] == 0x704        # ADS: not permitted
