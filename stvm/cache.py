"""A cache folder nobody else can poison: entries signed with a per-user key.

The compile cache stores pickled models and marshalled code objects; loading either runs code,
so an entry someone else wrote must never be loaded. Harmless in a private `~/.cache`,
dangerous when `STVM_CACHE_DIR` is a shared or CI cache folder.

* Every entry is `HMAC-SHA256(key, name + payload) || payload`; an entry whose tag does not
  verify (forged, truncated, renamed from another entry, written with another user's key) is
  treated as missing and rebuilt. Only the verified payload is unpickled.
* The key is 32 random bytes in a file of the user's own (`$XDG_CONFIG_HOME/stvm/cache.key`,
  default `~/.config/stvm/cache.key`, or `STVM_CACHE_KEY_FILE`), created with mode 0600 in a
  0700 folder, never inside the cache folder. A key file that others can read or write, or
  that belongs to another user, disables the cache with a warning.
* A cache folder (or the folder holding it, unless that one has the sticky bit, as /tmp does)
  that other users can write, or that another user owns, is refused with a warning: the run
  goes on without a cache.

`SignedCache(folder).get(name)` / `.put(name, payload)` is the one interface; the compile cache
(stvm/project.py) and any later parse or check cache use it.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import stat
import warnings
from pathlib import Path

from stvm.folders import default_folder, folder_problem as _folder_problem  # noqa: F401 (API: stvm.cache.default_folder)

TAG_BYTES = 32

MAX_ENTRY_BYTES = 512 * 2**20
"""The largest cache entry read (512 MiB; the compile cache of a 100,000-line project is tens of
MB). `STVM_CACHE_MAX_ENTRY_MB` changes it. A larger entry is treated as missing."""


def max_entry_bytes() -> int:
    text = os.environ.get("STVM_CACHE_MAX_ENTRY_MB", "")
    try:
        megabytes = int(text)
    except ValueError:
        return MAX_ENTRY_BYTES
    return megabytes * 2**20 if 0 < megabytes <= 1 << 20 else MAX_ENTRY_BYTES


def read_regular_file(path: Path, limit: int) -> bytes | None:
    """The bytes of `path` if it is a regular file (a symbolic link is not followed) of at most
    `limit` bytes, else None. Opened non-blocking, so a FIFO planted under the name cannot hang
    the reader; checked with fstat on the open descriptor, so nothing can be swapped in between;
    read up to its size, so /dev/zero or a growing file cannot exhaust memory."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
                     | getattr(os, "O_CLOEXEC", 0))
    except OSError:
        return None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode) or info.st_size > limit:
            return None
        chunks = []
        left = info.st_size
        while left > 0:
            chunk = os.read(fd, min(left, 1 << 24))
            if not chunk:
                break
            chunks.append(chunk)
            left -= len(chunk)
        return b"".join(chunks)
    except OSError:
        return None
    finally:
        os.close(fd)


class CacheWarning(UserWarning):
    """The cache cannot be used safely; the run goes on without it."""


_WARNED: set[str] = set()


def _warn(message: str) -> None:
    if message not in _WARNED:        # once per process: a run loads the cache several times
        _WARNED.add(message)
        warnings.warn(message, CacheWarning, stacklevel=3)


def key_file() -> Path:
    explicit = os.environ.get("STVM_CACHE_KEY_FILE")
    if explicit:
        return Path(explicit)
    return Path(os.environ.get("XDG_CONFIG_HOME") or Path.home() / ".config") / "stvm" / "cache.key"


def _load_key(path: Path) -> bytes | None:
    """The user's key, created on first use; None (with a warning) if it cannot be trusted."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
    except FileNotFoundError:
        return _create_key(path)
    except OSError as exc:
        _warn(f"compile cache disabled: cannot read the cache key {path}: {exc.strerror or exc}")
        return None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode) or info.st_uid != os.getuid() or info.st_mode & 0o077:
            _warn(f"compile cache disabled: the cache key {path} must be a file of yours with mode 0600 "
                  f"(it is {stat.S_IMODE(info.st_mode):o}, uid {info.st_uid})")
            return None
        key = os.read(fd, 4096)
    finally:
        os.close(fd)
    if len(key) < TAG_BYTES:
        _warn(f"compile cache disabled: the cache key {path} is damaged (delete it to make a new one)")
        return None
    return key


def _create_key(path: Path) -> bytes | None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except FileExistsError:       # another stvm made it meanwhile
        return _load_key(path)
    except OSError as exc:
        _warn(f"compile cache disabled: cannot create the cache key {path}: {exc.strerror or exc}")
        return None
    import secrets   # lazy: start-up (only when the key is created)
    key = secrets.token_bytes(TAG_BYTES)
    try:
        os.write(fd, key)
    finally:
        os.close(fd)
    return key


class SignedCache:
    """Entries named by the caller (a content hash), verified with the user's key."""

    def __init__(self, folder: Path | None = None, key_path: Path | None = None) -> None:
        self.folder = Path(folder) if folder is not None else default_folder()
        self._key_path = key_path if key_path is not None else key_file()
        self._key: bytes | None = None
        self._checked = False
        self.usable = False

    def _ready(self) -> bool:
        if not self._checked:
            self._checked = True
            problem = _folder_problem(self.folder)
            if problem:
                _warn(f"compile cache not used: {problem}")
            else:
                self._key = _load_key(self._key_path)
                self.usable = self._key is not None
        return self.usable

    def _tag(self, name: str, payload: bytes) -> bytes:
        assert self._key is not None
        mac = hmac.new(self._key, name.encode() + b"\0", hashlib.sha256)
        mac.update(payload)   # not joined to the name: no copy of a payload of tens of MB
        return mac.digest()

    def path(self, name: str) -> Path:
        return self.folder / name

    def get(self, name: str) -> bytes | None:
        """The payload stored under `name`, or None if missing, damaged or not signed by us."""
        if not self._ready():
            return None
        data = read_regular_file(self.path(name), max_entry_bytes() + TAG_BYTES)
        if data is None:   # missing, not a regular file (link, FIFO, device, folder) or too large
            return None
        tag, payload = data[:TAG_BYTES], data[TAG_BYTES:]
        if len(tag) < TAG_BYTES or not hmac.compare_digest(tag, self._tag(name, payload)):
            return None
        try:
            os.utime(self.path(name))      # recently used: pruning drops the oldest first
        except OSError:
            pass
        return payload

    def put(self, name: str, payload: bytes) -> None:
        """Store `payload` under `name` (atomically; errors are ignored: a cache is optional)."""
        if not self._ready():
            return
        tmp = self.path(f"{name}.tmp{os.getpid()}")
        try:
            self.folder.mkdir(parents=True, exist_ok=True, mode=0o700)
            try:
                tmp.unlink()   # a leftover of a killed run with our pid (never followed if a link)
            except FileNotFoundError:
                pass
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o600)
            with os.fdopen(fd, "wb") as fh:
                fh.write(self._tag(name, payload))
                fh.write(payload)
            target = self.path(name)
            if target.is_dir() and not target.is_symlink():
                # a folder planted under the entry's name: replace() cannot overwrite it
                raise IsADirectoryError(str(target))
            tmp.replace(target)
        except OSError:
            try:   # no temporary file left behind, whatever failed
                tmp.unlink()
            except OSError:
                pass

    def prune(self, pattern: str, keep: int) -> None:
        """Keep the `keep` most recently used entries matching `pattern`."""
        if not self._ready():
            return
        try:
            entries = sorted(self.folder.glob(pattern), key=lambda p: p.stat().st_mtime)
        except OSError:
            return
        for old in entries[:-keep] if keep else entries:
            try:
                old.unlink()
            except OSError:
                pass
