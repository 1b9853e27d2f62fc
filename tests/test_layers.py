"""One-way stages: the import graph of `stvm/` and `emulator/`, read with `ast`.

Every import counts: at module level, inside a function, under `if TYPE_CHECKING:` (an import
moved into a function hides a cycle from Python, not from this test), and so does every package
an import runs on the way (`import stvm.stdlib.registry` runs `stvm/stdlib/__init__.py`). The test
fails on

- any cycle between modules,
- any import from a higher layer into a lower one (LAYERS, below, written once),
- any import of another module's `_private` name,
- an import inside a function without a `# lazy: ...` comment (on its line or above its block)
  saying why it is not at the top: start-up time is the one reason left, since no import can
  hide a cycle any more.

There is no exceptions list. `python tests/test_layers.py` prints every breach (nothing when the
tree is clean).

Where the order differs from the first sketch (source → syntax → semantics → lower → runtime →
stdlib → project → tools), the code showed why:

- `stvm.numeric` (REAL rounding, STRING fitting) sits at the bottom: the checker folds constants,
  the lowering writes initial values and the VM stores values with the same two functions.
- The stdlib's registry of natives stays in `stvm.stdlib`, above the runtime: its implementations
  need the runtime's values (FunctionError, ArrayRef) and the semantic types. The checker (result
  types of generic natives) and the VM (implementations) are given the tables by their caller,
  `stvm.project`, instead of importing them.
- `stvm` itself (the package: `stvm.load`, `stvm.VM`) is the API over everything, at the top.
- `stvm.run` (the run command) drives the demo, scenarios, HMI and OPC UA, so it sits with
  `stvm.cli` above every front end.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("stvm", "emulator")

# The layer order, lowest first. A module belongs to the longest entry that is its name or a
# package prefix of it; modules on one line (one layer) may import each other, without cycles.
# An import may only go to the same layer or a lower one.
LAYERS: list[tuple[str, ...]] = [
    ("emulator",),                       # the TM robot: knows nothing of stvm
    ("stvm.records",),                   # value records without dataclass's import cost
    ("stvm.version", "stvm.settings", "stvm.dialects"),   # the vendor profiles: data the settings read
    ("stvm.numeric",),                   # REAL rounding, STRING fitting: checker, lowering, runtime
    # spans, read_source, SourceError; the private cache folder and its signed entries; the collector's pause
    ("stvm.source", "stvm.folders", "stvm.cache", "stvm.heap"),
    ("stvm.diagnostics",),               # FILE:LINE:COL: error: message + excerpt
    ("stvm.syntax",),                    # grammar, AST nodes, literals, tree walks
    ("stvm.semantics",),                 # index, types, checker
    ("stvm.lower",),                     # Python source + line map
    ("stvm.runtime",),                   # VM, clock, tasks, faults
    ("stvm.stdlib",),                    # IEC + Omron natives, sockets, ST sources
    ("stvm.manifest", "stvm.libraries"),   # stvm.toml; library folders and their namespaces
    ("stvm.project", "stvm.cli_support"),   # the driver: load, check, lower, start; the commands' conventions
    ("stvm.lockstep", "stvm.scenario"),
    ("stvm.demo", "stvm.trace", "stvm.session"),   # a run: VM, robot, scenario, front ends
    ("stvm.debug", "stvm.frontend", "stvm.hmi", "stvm.opcua", "stvm.lint", "stvm.testrunner"),
    ("stvm.lsp",),                       # the language server: the checker's index, lint, live values
    # the commands: `stvm run` drives the demo, scenarios and every front end; `stvm` is the API
    ("stvm", "stvm.cli", "stvm.run", "stvm.__main__", "stvm.pytest_plugin"),
]
# `stvm` (the package) names only itself: its submodules are placed by their own entries.
ROOT_PACKAGE = "stvm"

# An import inside a function is there for start-up time only (the module is not needed on every
# path that loads the importer), and says so on its line or the line above: `# lazy: start-up`.
LAZY = "# lazy:"


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def modules() -> dict[str, Path]:
    found = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            found[_module_name(path)] = path
    return found


def _is_package(path: Path) -> bool:
    return path.name == "__init__.py"


class _Import:
    def __init__(self, importer, imported, name, line, where):
        self.importer, self.imported, self.name, self.line = importer, imported, name, line
        self.where = where      # "module", "function" or "typing" (under `if TYPE_CHECKING:`)


def _scan(node, where, found):
    for child in ast.iter_child_nodes(node):
        inner = where
        if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)) and where == "module":
            inner = "function"
        elif isinstance(child, ast.If) and _is_type_checking(child.test):
            for stmt in child.body:
                _scan_one(stmt, "typing", found)
            for stmt in child.orelse:
                _scan_one(stmt, where, found)
            continue
        _scan_one(child, inner, found)


def _scan_one(node, where, found):
    if isinstance(node, (ast.Import, ast.ImportFrom)):
        found.append((node, where))
    else:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)) and where == "module":
            where = "function"
        _scan(node, where, found)


def _is_type_checking(test) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or \
        (isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def imports(known: dict[str, Path]):
    """Every import of a project module, as _Import, with the packages it loads on the way.

    `import a.b.c` runs `a/__init__`, `a/b/__init__` and then `c`: each is an edge, except the
    packages that hold the importer (they are loaded before the importer runs)."""
    for name, path in known.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        package = name if _is_package(path) else name.rpartition(".")[0]
        found: list = []
        _scan(tree, "module", found)
        for node, where in found:
            targets = []   # (module, imported name or None)
            if isinstance(node, ast.Import):
                targets = [(alias.name, None) for alias in node.names]
            else:
                if node.level:
                    base = package.split(".")
                    if node.level > 1:
                        base = base[: -(node.level - 1)]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                for alias in node.names:
                    submodule = f"{target}.{alias.name}"
                    targets.append((submodule, None) if submodule in known else (target, alias.name))
            for module, imported_name in targets:
                if module.split(".")[0] not in PACKAGES:
                    continue
                parts = module.split(".")
                for depth in range(1, len(parts)):
                    ancestor = ".".join(parts[:depth])
                    if not (name == ancestor or name.startswith(ancestor + ".")):
                        yield _Import(name, ancestor, None, node.lineno, where)
                yield _Import(name, module, imported_name, node.lineno, where)


def function_level_imports(known: dict[str, Path]):
    """(file:line, text) of each import of a project module inside a function."""
    for name, path in known.items():
        lines = path.read_text(encoding="utf-8").splitlines()
        tree = ast.parse("\n".join(lines), str(path))
        found: list = []
        _scan(tree, "module", found)
        for node, where in found:
            if where != "function":
                continue
            modules_named = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or "." * node.level]
            if getattr(node, "level", 0) == 0 and not any(m.split(".")[0] in PACKAGES for m in modules_named):
                continue
            yield f"{path.relative_to(ROOT)}:{node.lineno}", lines[node.lineno - 1], \
                _said(lines, node.lineno - 1)


def _said(lines: list[str], index: int) -> bool:
    """A `# lazy:` comment on the import's line, or above the block of imports it is part of."""
    while index >= 0:
        text = lines[index].strip()
        if LAZY in text:
            return True
        if not (text.startswith(("from ", "import ", "#")) or text.endswith((",", "(")) or
                text.endswith(")") and not text.startswith(("def ", "if ", "return "))):
            return False
        index -= 1
    return False


def layer_of(module: str) -> int:
    best, best_len = None, -1
    for index, entries in enumerate(LAYERS):
        for entry in entries:
            prefix = entry != ROOT_PACKAGE and module.startswith(entry + ".")
            if (module == entry or prefix) and len(entry) > best_len:
                best, best_len = index, len(entry)
    if best is None:
        raise AssertionError(f"{module} is in no layer: add it to LAYERS")
    return best


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def problems() -> list[str]:
    known = modules()
    found: list[str] = []
    graph: dict[str, set[str]] = {name: set() for name in known}
    for edge in imports(known):
        importer, imported = edge.importer, edge.imported
        where = f"{known[importer].relative_to(ROOT)}:{edge.line}"
        if imported not in known:
            found.append(f"{where}: {importer} imports {imported}, which does not exist")
            continue
        if imported != importer:
            graph[importer].add(imported)
        if layer_of(imported) > layer_of(importer):
            found.append(f"{where}: {importer} (layer {layer_of(importer)}) imports "
                         f"{imported} (layer {layer_of(imported)}): against the order")
        if edge.name is not None and _private(edge.name) and imported != importer:
            found.append(f"{where}: {importer} imports the private name {imported}.{edge.name}")
    found.extend(f"cycle: {' -> '.join(cycle)}" for cycle in cycles(graph))
    for where, line, said in function_level_imports(known):
        if not said:
            found.append(f"{where}: an import inside a function without a `{LAZY} ...` comment "
                         f"saying why it is not at the top: {line.strip()}")
    return list(dict.fromkeys(found))


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """One cycle for each strongly connected component of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[list[str]] = []
    counter = 0

    def visit(start: str) -> None:
        nonlocal counter
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            for child in children:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == node:
                            break
                    if len(component) > 1:
                        components.append(sorted(component))

    for name in sorted(graph):
        if name not in index:
            visit(name)
    return [_one_cycle(graph, set(component)) for component in components]


def _one_cycle(graph: dict[str, set[str]], members: set[str]) -> list[str]:
    start = min(members)
    previous = {start: None}
    queue = [start]
    while queue:
        node = queue.pop(0)
        for child in sorted(graph[node] & members):
            if child == start:
                path = [node]
                while previous[path[-1]] is not None:
                    path.append(previous[path[-1]])
                return list(reversed(path)) + [start]
            if child not in previous:
                previous[child] = node
                queue.append(child)
    return sorted(members)


def test_every_module_has_a_layer():
    for name in modules():
        layer_of(name)


def test_imports_follow_the_layers():
    found = problems()
    assert not found, "\n".join(found)


def test_the_rules_themselves():
    # on a graph made up for the purpose
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert cycles(graph) == [["a", "b", "c", "a"]]
    assert cycles({"a": {"b"}, "b": set()}) == []
    # the order the stages run in
    assert layer_of("stvm.source") < layer_of("stvm.syntax.parser") < layer_of("stvm.semantics.checker") \
        < layer_of("stvm.lower.codegen") < layer_of("stvm.runtime.vm") < layer_of("stvm.stdlib.registry") \
        < layer_of("stvm.project") < layer_of("stvm.cli")
    assert layer_of("stvm.numeric") < layer_of("stvm.semantics.checker")
    assert layer_of("stvm") == layer_of("stvm.cli")            # the package is the API, at the top
    assert _private("_f32") and not _private("__version__") and not _private("f32")


def test_imports_are_found_wherever_they_are():
    tree = ast.parse("import stvm.a\n"
                     "if TYPE_CHECKING:\n    from stvm.b import B\n"
                     "def f():\n    from stvm.c import C   # lazy: start-up\n"
                     "class K:\n    def m(self):\n        import stvm.d\n")
    found: list = []
    _scan(tree, "module", found)
    where = {(node.names[0].name if isinstance(node, ast.Import) else node.module): kind for node, kind in found}
    assert where == {"stvm.a": "module", "stvm.b": "typing", "stvm.c": "function", "stvm.d": "function"}
    lines = ["def f():", "    # lazy: start-up", "    from a import b", "    from c import (d,", "        e)",
             "    x = 1", "    from f import g"]
    assert _said(lines, 2) and _said(lines, 3) and not _said(lines, 6)


if __name__ == "__main__":
    for line in problems():
        print(line)
    sys.exit(0)
