"""Where stvm keeps its private files (the signed compile cache, stvm/cache.py), and whether a
folder is safe for them: files there are unpickled, so nobody else may be able to write them.

The cache folder is `STVM_CACHE_DIR`, else `$XDG_CACHE_HOME/stvm`, else `~/.cache/stvm`. A folder
(or the folder holding it, unless that one has the sticky bit, as /tmp does) that other users can
write, or that another user owns, is not safe (`folder_problem` says why).
"""

from __future__ import annotations

import hashlib
import os
import stat
from pathlib import Path


def default_folder() -> Path:
    base = os.environ.get("STVM_CACHE_DIR")
    if base:
        return Path(base)
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "stvm"


def writable_by_others(info: os.stat_result) -> bool:
    return bool(info.st_mode & (stat.S_IWGRP | stat.S_IWOTH))


def folder_problem(folder: Path) -> str | None:
    """Why `folder` is not safe as a cache (None if it is, or does not exist yet)."""
    uid = os.getuid()
    try:
        info = folder.stat()
    except FileNotFoundError:
        info = None
    except OSError as exc:
        return f"cannot use the cache folder {folder}: {exc.strerror or exc}"
    if info is not None:
        if not stat.S_ISDIR(info.st_mode):
            return f"the cache folder {folder} is not a folder"
        if info.st_uid != uid:
            return f"the cache folder {folder} belongs to another user (uid {info.st_uid})"
        if writable_by_others(info):
            return (f"the cache folder {folder} is writable by other users (mode {stat.S_IMODE(info.st_mode):o}); "
                    f"chmod go-w it or set STVM_CACHE_DIR to a private folder")
    parent = folder.resolve().parent
    try:
        parent_info = parent.stat()
    except OSError:
        return None
    if writable_by_others(parent_info) and not parent_info.st_mode & stat.S_ISVTX and parent_info.st_uid != uid:
        return f"the cache folder's parent {parent} is writable by other users (they could replace the folder)"
    return None




def content_name(prefix: str, *parts: str, suffix: str = ".bin") -> str:
    """A file name keyed by the content it was built from (`prefix-<sha256 prefix>suffix`)."""
    digest = hashlib.sha256("\0".join(parts).encode("utf-8", "replace")).hexdigest()[:24]
    return f"{prefix}-{digest}{suffix}"


# --- files shipped inside the package (the prebuilt stdlib units, the parser's Lark tables): each
# built by `python -m stvm.stdlib.prebuilt`, trusted like the code, and headed by one ASCII line,
# the key of what it was built from, so a stale file is recognised and not used

def read_keyed(file: Path, key: str) -> bytes | None:
    """The body of `file` when its first line is `key`, else None (missing, stale or damaged)."""
    try:
        data = file.read_bytes()
    except OSError:
        return None
    stored_key, _, body = data.partition(b"\n")
    return body if stored_key.decode("ascii", "replace") == key else None


def write_keyed(file: Path, key: str, body: bytes) -> None:
    """Write `key` and `body` as `read_keyed` reads them, replacing `file` at once."""
    tmp = file.with_suffix(".tmp")
    tmp.write_bytes(key.encode("ascii") + b"\n" + body)
    tmp.replace(file)
