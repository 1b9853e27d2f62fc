"""The VS Code extension's side of check and lint diagnostics (VS Code itself cannot run here:
the server it starts is tested over stdio in test_lint_lsp.py)."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

EXT = Path(__file__).resolve().parents[2] / "editors" / "vscode"


def test_manifest_starts_on_st_files_and_declares_the_language_client():
    manifest = json.loads((EXT / "package.json").read_text())
    assert "onLanguage:structured-text" in manifest["activationEvents"]
    assert manifest["main"] == "./extension.js"
    assert "vscode-languageclient" in manifest["dependencies"]
    assert any(lang["id"] == "structured-text" and ".st" in lang["extensions"]
               for lang in manifest["contributes"]["languages"])
    props = manifest["contributes"]["configuration"]["properties"]
    assert props["stvm.lint.enable"]["default"] is True and props["stvm.command"]["default"] == ["stvm"]


def test_extension_starts_stvm_lsp_and_resolves_rule_links():
    source = (EXT / "extension.js").read_text()
    assert '"lsp"' in source and '"dap"' in source
    assert 'registerTextDocumentContentProvider("stvm-rule"' in source   # the stvm-rule: links of stvm lsp
    assert '"lint", "--explain"' in source


@pytest.mark.skipif(shutil.which("node") is None, reason="node is not installed: cannot syntax-check extension.js")
def test_extension_is_valid_javascript():
    proc = subprocess.run(["node", "--check", str(EXT / "extension.js")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
