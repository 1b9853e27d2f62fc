"""No unsigned deserialisation (issues 34 and 28.4): every place in `stvm/` and `emulator/` that
turns bytes into objects by a format that can run code (pickle, marshal, shelve/dbm, Lark's
saved tables, asyncua's address-space shelf, YAML's full loader) is listed here with why its
bytes are trusted. A new site fails this test until it is signed (stvm.cache.SignedCache) or
reads only files shipped inside the package, and is added below with its reason.

docs/security.md lists the same sites for readers.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

SIGNED = "verified with the user's HMAC key first (stvm.cache.SignedCache.get)"
SHIPPED = "a file inside the installed package, trusted like the code (stvm.folders.read_keyed)"

# (file, callee) -> (how many such calls, why their bytes are trusted). Keyed by file, not by
# function, so that moving code inside a module does not need an edit here; a new call does.
ALLOWED: dict[tuple[str, str], tuple[int, str]] = {
    # the compile cache: checked project, parsed units, stdlib units, lowered model + code objects
    ("stvm/project.py", "pickle.loads"): (4, SIGNED),
    ("stvm/project.py", "marshal.loads"): (1, SIGNED),
    ("stvm/stdlib/prebuilt.py", "pickle.loads"): (1, SHIPPED),  # prebuilt_units.pickle.z
    ("stvm/syntax/tables.py", "._load"): (1, (
        "Lark's loader given plain data decoded from JSON (the shipped st_tables.json, or a "
        "SignedCache entry of the same text): nothing is unpickled")),
}

_MODULES = {"pickle", "_pickle", "cPickle", "marshal", "shelve", "dbm", "yaml", "dill", "joblib",
            "jsonpickle", "numpy", "np", "torch"}
_LOADERS = {"load", "loads", "open", "Unpickler", "unsafe_load", "full_load", "load_all"}
_KEYWORDS = {"shelf_file"}   # asyncua Server.init(shelf_file=...): a shelve database


def _sites(path: Path) -> list[tuple[str, int]]:
    """(callee, line) of every deserialising call in `path`, with its enclosing function."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    imported: dict[str, str] = {}   # local name -> "module.name" for `from pickle import loads`
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module in _MODULES:
            for alias in node.names:
                if alias.name in _LOADERS:
                    imported[alias.asname or alias.name] = f"{node.module}.{alias.name}"
    found: list[tuple[str, str, int]] = []

    def visit(node: ast.AST, function: str) -> None:
        for child in ast.iter_child_nodes(node):
            name = child.name if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)) else function
            if isinstance(child, ast.Call):
                func = child.func
                callee = None
                if isinstance(func, ast.Attribute):
                    if isinstance(func.value, ast.Name) and func.value.id in _MODULES and func.attr in _LOADERS:
                        callee = f"{func.value.id}.{func.attr}"
                    elif func.attr == "_load":   # Lark's loader of saved (pickled) tables
                        callee = "._load"
                elif isinstance(func, ast.Name) and func.id in imported:
                    callee = imported[func.id]
                if callee is not None:
                    found.append((callee, function, child.lineno))
                for kw in child.keywords:
                    if kw.arg in _KEYWORDS:
                        found.append((f"{kw.arg}=", function, child.lineno))
                    if kw.arg == "cache" and isinstance(func, ast.Name) and func.id == "Lark" and not (
                            isinstance(kw.value, ast.Constant) and kw.value.value in (False, None)):
                        found.append(("Lark(cache=)", function, child.lineno))
            visit(child, name)

    visit(tree, "<module>")
    return found


def _all_sites() -> list[tuple[str, str, str, int]]:
    out = []
    for package in ("stvm", "emulator"):
        for path in sorted((ROOT / package).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            out += [(rel, function, callee, line) for callee, function, line in _sites(path)]
    return out


def test_every_deserialisation_site_is_signed_or_shipped() -> None:
    from collections import Counter
    counts = Counter((rel, callee) for rel, _, callee, _ in _all_sites())
    unlisted = [f"{rel}:{line} {function}: {callee}" for rel, function, callee, line in _all_sites()
                if counts[rel, callee] > ALLOWED.get((rel, callee), (0, ""))[0]]
    assert not unlisted, ("deserialisation of bytes not known to be trusted (sign them with "
                          "stvm.cache.SignedCache, then list the site here):\n" + "\n".join(unlisted))


def test_the_scan_sees_what_it_must(tmp_path) -> None:
    planted = tmp_path / "planted.py"
    planted.write_text("import pickle, marshal\nfrom pickle import loads as l\nfrom lark import Lark\n"
                       "def f(b, g):\n    pickle.load(b)\n    l(b)\n    marshal.loads(b)\n"
                       "    Lark(g, cache=True)\n    Lark.__new__(Lark)._load(b)\n"
                       "async def h(s, p):\n    await s.init(shelf_file=p)\n", encoding="utf-8")
    callees = sorted(callee for callee, _, _ in _sites(planted))
    assert callees == ["._load", "Lark(cache=)", "marshal.loads", "pickle.load", "pickle.loads", "shelf_file="]


def test_no_listed_site_is_stale() -> None:
    """A site that is gone leaves the list, so the list stays the true inventory."""
    present = {(rel, callee) for rel, _, callee, _ in _all_sites()}
    assert set(ALLOWED) - present == set()
