"""The `stvm` program (`stvm.cli.program`: the console script and `python -m stvm`) ends its
process without the collector's passes over the loaded project (issue 17, large inputs): what it
prints, writes and returns is `main`'s."""

from __future__ import annotations

import subprocess
import sys


def test_the_program_runs_main_then_freezes_the_heap_for_the_exit(tmp_path):
    program = tmp_path / "count.st"
    program.write_text("PROGRAM Main\nVAR n : INT; END_VAR\nn := n + 1;\nEND_PROGRAM\n")
    probe = ("import gc, sys\nimport stvm.cli\n"
             f"sys.argv = ['stvm', 'run', {str(program)!r}, '--cycles', '3', '--print', 'Main.n', '--no-cache']\n"
             "code = stvm.cli.program()\n"
             "print('frozen', gc.get_freeze_count() > 0, 'code', code)")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-2:] == ["Main.n = 3", "frozen True code 0"]


def test_python_dash_m_stvm_is_the_program(tmp_path):
    program = tmp_path / "count.st"
    program.write_text("PROGRAM Main\nVAR n : INT; END_VAR\nn := n + 2;\nEND_PROGRAM\n")
    done = subprocess.run([sys.executable, "-m", "stvm", "run", str(program), "--cycles", "2", "--print", "Main.n",
                           "--no-cache"], capture_output=True, text=True, timeout=120)
    assert (done.returncode, done.stdout.strip()) == (0, "Main.n = 4")
