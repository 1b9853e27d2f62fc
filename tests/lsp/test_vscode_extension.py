"""The VS Code extension (editors/vscode): its manifest, grammars and scripts, and the language
server started with the command line the extension builds, spoken to through the JSON-RPC layer
of vscode-languageclient (VS Code itself cannot run here: tests/lsp/vscode_client.js stubs the
few `vscode` calls that read the settings)."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys

import pytest

from lsp_helpers import FIXTURES, ROOT

EXT = ROOT / "editors" / "vscode"
NODE = shutil.which("node")


def manifest() -> dict:
    return json.loads((EXT / "package.json").read_text())


def test_manifest_declares_languages_grammars_commands_and_settings():
    m = manifest()
    c = m["contributes"]
    langs = {lang["id"]: lang for lang in c["languages"]}
    assert ".st" in langs["structured-text"]["extensions"]
    assert {".TcPOU", ".TcDUT", ".TcGVL", ".TcIO"} <= set(langs["twincat-xml"]["extensions"])
    assert "plcopen-xml" in langs
    for grammar in c["grammars"]:
        json.loads((EXT / grammar["path"]).read_text())           # every grammar file is there and JSON
    for lang in c["languages"]:
        json.loads((EXT / lang["configuration"]).read_text())
    commands = {cmd["command"] for cmd in c["commands"]}
    assert {"stvm.run", "stvm.trace", "stvm.lint", "stvm.test"} <= commands
    source = (EXT / "extension.js").read_text()
    for command in commands:
        assert f'registerCommand("{command}"' in source
    props = c["configuration"]["properties"]
    assert {"stvm.command", "stvm.dialect", "stvm.sysmac"} <= set(props)
    assert set(props["stvm.dialect"]["enum"]) == {"", "sysmac", "codesys", "twincat"}
    assert "vscode-languageclient" in m["dependencies"] and "@vscode/vsce" in m["devDependencies"]
    assert {f"onLanguage:{lang}" for lang in langs} <= set(m["activationEvents"])


def test_grammar_knows_the_dialects_keywords():
    grammar = (EXT / "syntaxes" / "structured-text.tmLanguage.json").read_text()
    for word in ("END_FUNCTION_BLOCK", "VAR_IN_OUT", "METHOD", "PROPERTY", "INTERFACE", "IMPLEMENTS",
                 "REFERENCE", "__QUERYINTERFACE", "UNION", "NAMESPACE", "AND_THEN", "LTIME", "SktTCPConnect"):
        assert word in grammar, word
    rules = json.loads(grammar)["repository"]
    control = re.compile(rules["keywords"]["patterns"][0]["match"].replace("(?i)", ""), re.I)
    assert control.search("elsif x then") and not control.search("ELSIFY")


def test_build_script_and_gitignore():
    script = (EXT / "build.sh").read_text()
    assert "vsce package" in script and "npm ci" in script
    ignored = (ROOT / ".gitignore").read_text()
    assert "editors/vscode/node_modules/" in ignored and "editors/vscode/*.vsix" in ignored


@pytest.mark.skipif(NODE is None, reason="node is not installed")
def test_extension_is_valid_javascript():
    proc = subprocess.run([NODE, "--check", str(EXT / "extension.js")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr


@pytest.mark.skipif(NODE is None or not (EXT / "node_modules" / "vscode-jsonrpc").exists(),
                    reason="needs node and editors/vscode/node_modules (editors/vscode/build.sh installs them)")
def test_the_extensions_command_line_starts_a_server_that_answers():
    main = FIXTURES / "oo" / "main.st"
    settings = {"command": [sys.executable, "-m", "stvm"], "dialect": "sysmac", "sysmac": ["iec_pin_aliases=on"]}
    proc = subprocess.run([NODE, str(ROOT / "tests" / "lsp" / "vscode_client.js"), str(EXT), str(main), "4", "6",
                           json.dumps(settings)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    answer = json.loads(proc.stdout.strip().splitlines()[-1])
    assert answer["args"][-5:] == ["lsp", "--sysmac", "dialect=sysmac", "--sysmac", "iec_pin_aliases=on"]
    assert {s["language"] for s in answer["selector"]} == {"structured-text", "twincat-xml", "plcopen-xml"}
    assert {"hoverProvider", "definitionProvider", "completionProvider", "renameProvider"} <= set(answer["capabilities"])
    assert "(VAR) Main.delay : TON" in answer["hover"]["contents"]["value"]
    assert answer["definition"][0]["range"]["start"] == {"line": 4, "character": 4}
    assert answer["completion"] > 0 and answer["diagnostics"] == []
