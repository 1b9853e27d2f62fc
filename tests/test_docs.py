"""The documentation stands alone: the site builds with every link resolved, the README's links
point at files of the repository, and no page sends a reader to a file outside it."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
MARKDOWN_LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")


def test_site_builds_with_every_link_resolved(tmp_path):
    pytest.importorskip("mkdocs", reason="mkdocs comes with the [test] and [docs] extras")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet",
                           "--site-dir", str(tmp_path / "site")],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr


def test_readme_links_point_at_files_of_the_repository():
    missing = [target for target in MARKDOWN_LINK.findall(README.read_text(encoding="utf-8"))
               if not target.startswith(("http://", "https://")) and not (ROOT / target).exists()]
    assert missing == []


def test_readme_is_short():
    # the manual lives in docs/; the README is what stvm is, the two commands and a tour
    assert len(README.read_text(encoding="utf-8").splitlines()) <= 300


def test_no_page_or_source_sends_a_reader_outside_the_repository():
    # a user's clone has only the repository: the specs and seeds stvm was built from are restated
    # in docs/ (sysmac.md, tm_protocol.md) and named by their titles, never by a path beside it
    outside = re.compile(r"\.\./shared|shared/(?:spec|seeds|vendor)/")
    places = [README, *sorted((ROOT / "docs").glob("*.md"))]
    for folder, suffixes in (("st_src", (".st", ".md", ".toml")), ("stvm", (".py", ".st", ".lark")),
                             ("emulator", (".py",)), ("editors", (".json", ".js", ".md"))):
        places += [p for p in sorted((ROOT / folder).rglob("*")) if p.suffix in suffixes and "node_modules" not in p.parts]
    found = [f"{p.relative_to(ROOT)}:{n}" for p in places
             for n, line in enumerate(p.read_text(encoding="utf-8", errors="replace").splitlines(), 1)
             if outside.search(line)]
    assert found == []
