"""What `stvm` imports before it knows the command: a check-on-save or a CI matrix of small runs
pays it on every call (issue 16, start-up; figures in bench/bench_startup.py). Registering the
`trace`, `debug` and `lint` sub-commands must not load their machinery, and a run served from the
cache must not load the parser, the checker, the lowering's code generator or numpy."""

from __future__ import annotations

import json
import subprocess
import sys

HEAVY_AT_REGISTRATION = ("numpy", "stvm.trace.golden", "stvm.trace.run", "stvm.trace.recorder",
                         "stvm.lint.context", "stvm.lint.cfg", "stvm.syntax.nodes", "stvm.project")
HEAVY_FOR_A_CACHED_RUN = ("numpy", "stvm.syntax.parser", "stvm.syntax.nodes", "stvm.semantics.checker",
                          "stvm.lower.codegen", "stvm.trace.golden", "stvm.lint.context", "emulator",
                          "stvm.opcua.config")


def loaded_after(code: str) -> set[str]:
    probe = f"import json, sys\n{code}\nprint(json.dumps(sorted(sys.modules)))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return set(json.loads(done.stdout.strip().splitlines()[-1]))


def test_building_the_command_line_parser_loads_no_sub_command_machinery():
    loaded = loaded_after("import stvm.cli\nstvm.cli.build_parser()")
    assert loaded.isdisjoint(HEAVY_AT_REGISTRATION), sorted(loaded & set(HEAVY_AT_REGISTRATION))


def test_a_run_from_the_cache_loads_neither_front_end_nor_numpy(tmp_path):
    program = tmp_path / "tiny.st"
    program.write_text("PROGRAM Main\nVAR n : INT; END_VAR\nn := n + 1;\nEND_PROGRAM\n")
    env_cache = tmp_path / "cache"
    code = (f"import os\nos.environ['STVM_CACHE_DIR'] = {str(env_cache)!r}\n"
            "import contextlib, io\nimport stvm.cli\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            f"    assert stvm.cli.main(['run', {str(program)!r}, '--cycles', '1']) == 0")
    loaded_after(code)                 # fills the cache
    loaded = loaded_after(code)        # served from it
    assert loaded.isdisjoint(HEAVY_FOR_A_CACHED_RUN), sorted(loaded & set(HEAVY_FOR_A_CACHED_RUN))
