"""CI runs every benchmark of `python -m bench` in its smoke version (seconds), so none rots: a
figure whose code broke (an API it uses changed, a file moved) fails here. The numbers of a smoke
run mean nothing and nothing here looks at them; the figures are checked by running
`python -m bench` on a quiet machine (docs/benchmarks.md)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def run_bench(*args: str, tmp_path: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    env.setdefault("STVM_CACHE_DIR", str(tmp_path / "cache"))
    return subprocess.run([sys.executable, "-m", "bench", *args], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=600)


def test_every_figure_runs_in_its_smoke_version_and_is_recorded(tmp_path):
    listed = run_bench("--list", tmp_path=tmp_path)
    assert listed.returncode == 0, listed.stderr
    names = [line.split("  ")[0].strip() for line in listed.stdout.splitlines() if line.strip()]
    assert names, listed.stdout
    history = tmp_path / "history.jsonl"
    done = run_bench("--smoke", "--history", str(history), tmp_path=tmp_path)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-4000:]
    assert "machine:" in done.stdout and "| figure |" in done.stdout
    assert "ERROR" not in done.stdout
    for name in names:   # each figure reported that it ran (stderr: "NAME: N row(s)")
        assert f"{name}: " in done.stderr, name
    import json
    record = json.loads(history.read_text().splitlines()[-1])
    assert record["smoke"] is True and record["machine"]["cores"] and record["rows"]
    assert all(row["yard_name"] for row in record["rows"]), "every row names its yardstick"
