"""The stdlib's parsed units, built once and shipped with stvm (start-up time of a cold run).

Parsing the stdlib's ~66 KB of ST is most of a first `stvm check` with an empty cache. The units
the parser makes of it with the default settings are stored beside this module
(`prebuilt_units.pickle.z`), under a key: stvm's version, the stdlib text itself, the settings,
and the code of every module the parse result depends on (the grammar and parser, the tree
nodes, spans, diagnostics, settings). A key that does not match (another stvm, other settings,
an edited grammar) means the file is not used: the stdlib is parsed (and cached per user) as
before, so a stale file costs time, never correctness.

Trust: the file is part of the installed package, like its `.py` files (whoever can replace it
can replace those); it is only read from this folder, never from a cache folder.

Rebuild it after changing the grammar, the parser, the nodes or the stdlib (this also regenerates
the parser's shipped Lark tables, stvm/syntax/tables.py); each file is written only when its
inputs changed, and the same inputs give the same bytes:

    python -m stvm.stdlib.prebuilt [--check]   (tests/stdlib/test_prebuilt.py says when it is stale)
"""

from __future__ import annotations

import hashlib
import pickle
import zlib
from pathlib import Path

from stvm.folders import read_keyed, write_keyed
from stvm.settings import DEFAULT_SETTINGS
from stvm.version import __version__

FILE = Path(__file__).with_name("prebuilt_units.pickle.z")

# what the parse result depends on, beside the stdlib text and the settings (relative to stvm/)
_PARSE_CODE = ("syntax", "source.py", "diagnostics", "settings.py", "version.py")


def _code_files(package: Path) -> list[Path]:
    files = []
    for name in _PARSE_CODE:
        path = package / name
        if path.is_dir():
            files += sorted(p for p in path.rglob("*") if p.suffix in (".py", ".lark")
                            and "__pycache__" not in p.parts)
        else:
            files.append(path)
    return files


def key(texts: list[tuple[str, str]], settings) -> str:
    package = Path(__file__).resolve().parent.parent
    digest = hashlib.sha256(b"stdlib-prebuilt\0" + __version__.encode() + b"\0" + repr(settings).encode())
    for path in _code_files(package):
        digest.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes())
    for name, text in texts:
        digest.update(name.encode() + b"\0" + text.encode("utf-8", "replace") + b"\0")
    return digest.hexdigest()


def load(texts: list[tuple[str, str]], settings):
    """(units, diagnostics) of the shipped stdlib parse when it matches `texts` and `settings`
    exactly, else None."""
    body = read_keyed(FILE, key(texts, settings))
    if body is None:
        return None
    try:
        units, diags = pickle.loads(zlib.decompress(body))
    except Exception:   # damaged, or classes that changed: parse instead
        return None
    return units, diags


def build(file: Path = FILE) -> bool:
    """Parse the stdlib with the default settings and write `file`, unless it already holds exactly
    these bytes; True when it was written. Reproducible: the same inputs give the same bytes (the
    module's `__main__` runs under PYTHONHASHSEED=0, so no set is pickled in another order)."""
    from stvm.stdlib import stdlib_sources   # lazy: stvm.stdlib imports this module
    from stvm.syntax.parser import parse_text   # lazy: start-up (lark)
    texts = stdlib_sources(DEFAULT_SETTINGS)
    units, diags = [], []
    for name, text in texts:
        unit, d = parse_text(text, name, DEFAULT_SETTINGS)
        units.append(unit)
        diags += d
    body = zlib.compress(pickle.dumps((units, diags), protocol=pickle.HIGHEST_PROTOCOL), 9)
    built_key = key(texts, DEFAULT_SETTINGS)
    if read_keyed(file, built_key) == body:
        return False
    write_keyed(file, built_key, body)
    return True


def main(argv: list[str]) -> int:
    """`python -m stvm.stdlib.prebuilt [--check]`: regenerate (or check) the parser tables and the
    stdlib units, each only when its inputs changed."""
    import os
    import subprocess
    import sys
    if os.environ.get("PYTHONHASHSEED") != "0":   # reproducible: re-run with a fixed string hash
        return subprocess.run([sys.executable, "-m", "stvm.stdlib.prebuilt", *argv],
                              env={**os.environ, "PYTHONHASHSEED": "0"}).returncode
    from stvm.syntax import gen_tables   # lazy: the generator imports the parser (lark), only for this command
    if "--check" in argv:   # the tables first: the stdlib parse below uses them
        stale = gen_tables.main(["--check"]) != 0
        import tempfile
        with tempfile.TemporaryDirectory() as folder:
            copy = Path(folder) / FILE.name
            if FILE.exists():
                copy.write_bytes(FILE.read_bytes())
            if build(copy):
                print(f"{FILE} is not what the build writes: run `python -m stvm.stdlib.prebuilt`", file=sys.stderr)
                stale = True
        return 1 if stale else 0
    gen_tables.main([])
    print(f"{'wrote' if build() else 'unchanged:'} {FILE}")
    return 0


if __name__ == "__main__":
    import sys
    raise SystemExit(main(sys.argv[1:]))
