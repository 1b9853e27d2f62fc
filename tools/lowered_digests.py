"""Digests of the generated Python for the thesis and the trace corpus, under every lowering option
variant and a few settings: run it in two checkouts and `diff` the outputs to show that a change of
the lowering leaves the generated code byte-identical (issue 18: the analysis pass).

Run: python tools/lowered_digests.py [PATH ...]   (default: st_src/PnP_Example.st, st_src, tests/trace/st/*.st)

The checkout's own folder is cut out of the code before hashing (string-overflow sites name their
file), so two checkouts of the same sources give the same digests.
"""

from __future__ import annotations

import hashlib
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from stvm.lower.codegen import Lowerer  # noqa: E402
from stvm.lower.options import DEFAULT_OPTIONS, LowerOptions  # noqa: E402
from stvm.project import check, project_settings  # noqa: E402

VARIANTS = {"default": DEFAULT_OPTIONS, "none": LowerOptions.none()} | {
    f"no_{name}": DEFAULT_OPTIONS.without(name) for name in LowerOptions.names()}
OVERRIDES = [[], ["array_oob=skip_statement"], ["for_end_eval=each"], ["open_array_bounds=actual"]]


def main(argv: list[str]) -> int:
    projects = [[Path(p)] for p in argv] or [[ROOT / "st_src" / "PnP_Example.st"], [ROOT / "st_src"]] + [
        [p] for p in sorted((ROOT / "tests" / "trace" / "st").glob("*.st"))]
    for paths in projects:
        for overrides in OVERRIDES:
            settings = project_settings(paths, overrides)
            analysis, diags, _ = check(paths, settings, use_cache=False)
            label = f"{paths[0].name} {','.join(overrides) or '-'}"
            if analysis is None:
                print(label, "does not check")
                continue
            for name, options in VARIANTS.items():
                source = Lowerer(analysis, settings, options).lower().source.replace(str(ROOT), "<root>")
                print(label, name, hashlib.sha256(source.encode()).hexdigest()[:16])
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
