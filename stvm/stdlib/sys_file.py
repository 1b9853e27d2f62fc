"""The CODESYS SysFile / SysDir libraries (declarations in sys_file.st, loaded under
`--dialect twincat`) on real files, confined to one folder: the run's file root.

The file root (docs/platform_libraries.md, "Files"): `--files-root DIR` of `stvm run`, else
`root` of the `[files]` table of stvm.toml (relative to the manifest), else the folder
`stvm_files` beside the manifest, else (no manifest) a fresh temporary folder of the run. Every
name an ST program gives is a path inside it: `/` or `\\` separate folders; a relative name is
relative to the root; TwinCAT's path placeholders at the start (%TC_BOOTPRJPATH%, %TC_TARGETPATH%,
%TC_INSTALLPATH%, %TC_CONFIGPATH%) stand for the root; an absolute path is allowed only when it
lies inside the root; a drive-letter path (`C:\\...`), a `..` part, or a path that leaves the root
through a symbolic link is refused (the function fails with ERR_NO_ACCESS_RIGHTS, as the runtime
answers an access it does not allow). The root is created when a file is first opened for writing
or a folder first made.

References (CODESYS online help, content.helpme-codesys.com/en/libs/): SysFile "SysFileOpen"
(AM_READ fails if the file does not exist, AM_WRITE creates or empties it, AM_APPEND needs the
file, AM_APPEND_PLUS creates it), "SysFileClose", "SysFileWrite"/"SysFileRead" (return the
number of bytes, the error in pResult^), "SysFileDelete"; SysDir "SysDirCreate", "SysDirDelete";
CmpErrors "Errors" (the codes). A handle is a small number (1, 2, ...); RTS_INVALID_HANDLE is
all bits set.
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

from stvm.lower.bind import st_names
from stvm.runtime.memory import MemoryFault, Ptr
from stvm.stdlib.registry import native_fb, native_function

ERR_OK, ERR_FAILED, ERR_PARAMETER = 0x0, 0x1, 0x2
ERR_INVALID_HANDLE, ERR_NO_ACCESS_RIGHTS, ERR_NO_OBJECT = 0x10, 0x1A, 0x1D
INVALID_HANDLE = 0xFFFFFFFFFFFFFFFF
AM_READ, AM_WRITE, AM_APPEND, AM_READ_PLUS, AM_WRITE_PLUS, AM_APPEND_PLUS = 0x1, 0x2, 0x4, 0x8, 0x10, 0x20
# (Python open mode, must the file exist)
_MODES = {AM_READ: ("rb", True), AM_WRITE: ("wb", False), AM_APPEND: ("ab", True),
          AM_READ_PLUS: ("r+b", True), AM_WRITE_PLUS: ("w+b", False), AM_APPEND_PLUS: ("a+b", False)}
_PLACEHOLDER = re.compile(r"%TC_(BOOTPRJPATH|TARGETPATH|INSTALLPATH|CONFIGPATH)%", re.IGNORECASE)
_DRIVE = re.compile(r"\A[A-Za-z]:")


class AccessRefused(Exception):
    """A name that would reach outside the file root."""


class FileRoot:
    """The folder an ST program's files live in, and the files it has open."""

    def __init__(self, root: Path | None) -> None:
        self._root = root
        self.handles: dict[int, object] = {}
        self.next_handle = 1

    @property
    def root(self) -> Path:
        if self._root is None:   # no manifest, no --files-root: a folder of this run
            self._root = Path(tempfile.mkdtemp(prefix="stvm-files-"))
        return self._root

    def path(self, name: bytes, create_root: bool = False) -> Path:
        """The file `name` (an ST STRING) stands for, inside the root; AccessRefused otherwise."""
        text = name.split(b"\0", 1)[0].decode("latin-1")
        placeholder = _PLACEHOLDER.match(text)
        if placeholder:
            text = text[placeholder.end():]
        text = text.replace("\\", "/")
        absolute = not placeholder and (text.startswith("/") or _DRIVE.match(text) is not None)
        parts = [p for p in text.split("/") if p not in ("", ".")]
        if not parts or any(p == ".." for p in parts) or _PLACEHOLDER.search(text):
            raise AccessRefused(text)
        root = self.root
        if create_root:
            root.mkdir(parents=True, exist_ok=True)
        real_root = root.resolve()
        if absolute:   # allowed only inside the root
            if _DRIVE.match(text):
                raise AccessRefused(text)
            try:
                parts = list(Path(text).resolve().relative_to(real_root).parts)
            except ValueError:
                raise AccessRefused(text) from None
            if not parts:
                raise AccessRefused(text)
        target = root.joinpath(*parts)
        # a symbolic link on the way (or the file itself) must not lead out of the root
        resolved = target.resolve()
        if resolved != real_root and real_root not in resolved.parents:
            raise AccessRefused(text)
        return target

    def open(self, name: bytes, mode: int) -> tuple[int, int]:
        """(handle, error) of SysFileOpen."""
        how = _MODES.get(mode)
        if how is None:
            return INVALID_HANDLE, ERR_PARAMETER
        pymode, must_exist = how
        try:
            path = self.path(name, create_root=not must_exist)
        except AccessRefused:
            return INVALID_HANDLE, ERR_NO_ACCESS_RIGHTS
        if must_exist and not path.is_file():
            return INVALID_HANDLE, ERR_NO_OBJECT
        try:
            handle = open(path, pymode)   # noqa: SIM115 -- closed by SysFileClose or close_all
        except OSError:
            return INVALID_HANDLE, ERR_FAILED
        number = self.next_handle
        self.next_handle += 1
        self.handles[number] = handle
        return number, ERR_OK

    def close_all(self) -> None:
        for handle in self.handles.values():
            handle.close()
        self.handles.clear()


def file_root(ctx) -> FileRoot:
    files = getattr(ctx, "files", None)
    if files is None:
        files = ctx.files = FileRoot(None)
    return files


def default_root(manifest: dict, root: Path | None) -> Path | None:
    """The file root a project's manifest gives (see the module's docstring)."""
    table = manifest.get("files", {}) if isinstance(manifest, dict) else {}
    configured = table.get("root") if isinstance(table, dict) else None
    if configured:
        return (Path(root or ".") / configured)
    return Path(root) / "stvm_files" if root is not None and manifest else None


def install_files(vm, project, override: str | os.PathLike | None = None) -> None:
    """Give `vm`'s natives their file root (twincat dialect)."""
    manifest = getattr(project, "manifest", {}) or {}
    root = Path(override) if override is not None else default_root(manifest, getattr(project, "root", None))
    vm.ctx.files = FileRoot(root)


def _set_result(ptr, code: int) -> None:
    if ptr is not None and hasattr(ptr, "set"):
        ptr.set(code)


def read_bytes(ptr, size: int) -> bytes | None:
    """`size` bytes at a POINTER TO BYTE: an ARRAY OF BYTE (the pointer to its first element, or
    to one element of it) or a STRING (its characters, then NULs), or any byte address the memory
    model makes (stvm/runtime/memory.py: a cast or moved pointer); None for anything else."""
    if type(ptr) is Ptr:
        try:
            return ptr.read(size)
        except MemoryFault:
            return None
    if type(ptr) is list:
        lst, start = ptr, 0
    elif hasattr(ptr, "lst") and hasattr(ptr, "index"):
        lst, start = ptr.lst, ptr.index
    elif hasattr(ptr, "get"):
        value = ptr.get()
        if isinstance(value, bytes):
            return (value + b"\0" * size)[:size]
        return None
    else:
        return None
    chunk = lst[start:start + size]
    if not all(isinstance(v, int) for v in chunk):
        return None
    return bytes(v & 0xFF for v in chunk)


def write_bytes(ptr, data: bytes) -> bool:
    """Store `data` at a POINTER TO BYTE (an ARRAY OF BYTE or one of its elements, or a byte
    address of the memory model)."""
    if type(ptr) is Ptr:
        try:
            ptr.write(data)
        except MemoryFault:
            return False
        return True
    if type(ptr) is list:
        lst, start = ptr, 0
    elif hasattr(ptr, "lst") and hasattr(ptr, "index"):
        lst, start = ptr.lst, ptr.index
    else:
        return False
    lst[start:start + len(data)] = list(data)
    return True


@native_function("SysFileOpen")
def sys_file_open(ctx, name: bytes, mode: int, p_result) -> int:
    handle, error = file_root(ctx).open(name, mode)
    _set_result(p_result, error)
    return handle


@native_function("SysFileClose")
def sys_file_close(ctx, handle: int) -> int:
    f = file_root(ctx).handles.pop(handle, None)
    if f is None:
        return ERR_INVALID_HANDLE
    f.close()
    return ERR_OK


class _BadBuffer(Exception):
    """The buffer of SysFileRead/SysFileWrite is not bytes the memory model can read or write."""


def _file_io(ctx, handle: int, p_result, transfer) -> int:
    """What SysFileRead and SysFileWrite share: the handle's file, `transfer(file)` (the number of
    bytes moved), and the error in pResult^ (ERR_INVALID_HANDLE for an unknown handle,
    ERR_PARAMETER for a buffer that is not bytes, ERR_FAILED when the file operation fails); the
    count is 0 on any error."""
    f = file_root(ctx).handles.get(handle)
    if f is None:
        code, count = ERR_INVALID_HANDLE, 0
    else:
        try:
            code, count = ERR_OK, transfer(f)
        except _BadBuffer:
            code, count = ERR_PARAMETER, 0
        except OSError:
            code, count = ERR_FAILED, 0
    _set_result(p_result, code)
    return count


@native_function("SysFileWrite")
def sys_file_write(ctx, handle: int, buffer, size: int, p_result) -> int:
    def write(f) -> int:
        data = read_bytes(buffer, size)
        if data is None:
            raise _BadBuffer
        f.write(data)
        f.flush()
        return len(data)
    return _file_io(ctx, handle, p_result, write)


@native_function("SysFileRead")
def sys_file_read(ctx, handle: int, buffer, size: int, p_result) -> int:
    def read(f) -> int:
        data = f.read(size)
        if not write_bytes(buffer, data):
            raise _BadBuffer
        return len(data)
    return _file_io(ctx, handle, p_result, read)


@native_function("SysFileDelete")
def sys_file_delete(ctx, name: bytes) -> int:
    try:
        path = file_root(ctx).path(name)
    except AccessRefused:
        return ERR_NO_ACCESS_RIGHTS
    if not path.is_file():
        return ERR_NO_OBJECT
    try:
        path.unlink()
    except OSError:
        return ERR_FAILED
    return ERR_OK


@native_function("SysDirCreate")
def sys_dir_create(ctx, name: bytes) -> int:
    try:
        path = file_root(ctx).path(name, create_root=True)
    except AccessRefused:
        return ERR_NO_ACCESS_RIGHTS
    try:
        path.mkdir()
    except FileExistsError:
        return ERR_FAILED
    except OSError:
        return ERR_NO_OBJECT
    return ERR_OK


@native_function("SysDirDelete")
def sys_dir_delete(ctx, name: bytes) -> int:
    try:
        path = file_root(ctx).path(name)
    except AccessRefused:
        return ERR_NO_ACCESS_RIGHTS
    try:
        path.rmdir()
    except FileNotFoundError:
        return ERR_NO_OBJECT
    except OSError:
        return ERR_FAILED
    return ERR_OK


# ---- Tc2_System file FBs (Tc2_System "FB_FileOpen", "FB_FileClose", "FB_FileDelete") --------------
# ADS return codes (Beckhoff "ADS Return Codes"): 0x70C not found, 0x704 reading/writing not
# permitted, 0x70B invalid parameter values, 0x700 general device error; Choice: an unknown
# handle is 0x70B.
ADS_NOT_FOUND, ADS_NOT_PERMITTED, ADS_INVALID_PARAM, ADS_DEVICE_ERROR = 0x70C, 0x704, 0x70B, 0x700
FOPEN_READ, FOPEN_WRITE, FOPEN_APPEND, FOPEN_PLUS = 0x1, 0x2, 0x4, 0x8
# nMode (fopen's r, w, a, r+, w+, a+; binary/text flags change nothing here) -> SysFile's mode
_FOPEN = {FOPEN_READ: AM_READ, FOPEN_WRITE: AM_WRITE, FOPEN_APPEND: AM_APPEND_PLUS,
          FOPEN_READ | FOPEN_PLUS: AM_READ_PLUS, FOPEN_WRITE | FOPEN_PLUS: AM_WRITE_PLUS,
          FOPEN_APPEND | FOPEN_PLUS: AM_APPEND_PLUS}
_ADS_OF = {ERR_NO_OBJECT: ADS_NOT_FOUND, ERR_NO_ACCESS_RIGHTS: ADS_NOT_PERMITTED,
           ERR_PARAMETER: ADS_INVALID_PARAM, ERR_INVALID_HANDLE: ADS_INVALID_PARAM}


@st_names("bBusy", "bError", "nErrId")
def _done(inst, error: int) -> None:
    inst.bBusy = False
    inst.bError = error != ERR_OK
    inst.nErrId = _ADS_OF.get(error, ADS_DEVICE_ERROR) if error != ERR_OK else 0


@native_fb("FB_FileOpen")
@st_names("sPathName", "nMode", "bExecute", "bBusy", "bError", "nErrId", "hFile", "bLast")
class FileOpen:
    """At a rising edge of bExecute: the file opened in the file root; hFile its handle (1 ...)."""

    def call(self, inst, ctx) -> None:
        edge = inst.bExecute and not inst.bLast
        inst.bLast = inst.bExecute
        if not edge:
            return
        mode = _FOPEN.get(inst.nMode & (FOPEN_READ | FOPEN_WRITE | FOPEN_APPEND | FOPEN_PLUS))
        if mode is None:
            _done(inst, ERR_PARAMETER)
            return
        handle, error = file_root(ctx).open(inst.sPathName, mode)
        inst.hFile = handle if error == ERR_OK else 0
        _done(inst, error)


@native_fb("FB_FileClose")
@st_names("hFile", "bExecute", "bBusy", "bError", "nErrId", "bLast")
class FileClose:
    def call(self, inst, ctx) -> None:
        edge = inst.bExecute and not inst.bLast
        inst.bLast = inst.bExecute
        if edge:
            _done(inst, sys_file_close(ctx, inst.hFile))


@native_fb("FB_FileDelete")
@st_names("sPathName", "bExecute", "bBusy", "bError", "nErrId", "bLast")
class FileDelete:
    def call(self, inst, ctx) -> None:
        edge = inst.bExecute and not inst.bLast
        inst.bLast = inst.bExecute
        if edge:
            _done(inst, sys_file_delete(ctx, inst.sPathName))
