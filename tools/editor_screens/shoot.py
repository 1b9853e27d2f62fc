"""Screenshots of `stvm lsp` answering in a real editor, for docs/editor.md: Monaco (the editor
core of VS Code, npm `monaco-editor`) in Debian's headless Chromium (Playwright), connected to
the real `stvm lsp` through bridge.py. Not VS Code itself, which cannot run on the build machine.

    python tools/editor_screens/shoot.py [--out docs/editor-screens] [--keep-npm DIR]

Runs `npm install monaco-editor` into a temporary folder (nothing of it is committed), opens
st_src/PnP_Example.st and triggers each feature with the editor's own actions: hover
(`editor.action.showHover`), completion (typing `.`), signature help
(`editor.action.triggerParameterHints`), definition (`editor.action.peekDefinition`), and the
live values (inlay hints) while
`stvm run st_src/PnP_Example.st --scan 1ms --opcua …` runs.
"""

from __future__ import annotations

import argparse
import json
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(HERE))
import bridge  # noqa: E402  (a sibling script, not a package)

MONACO = "monaco-editor@0.52.2"
CHROMIUM = "/usr/bin/chromium"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-dev-shm-usage"]
SOURCE = ROOT / "st_src" / "PnP_Example.st"
VIEWPORT = {"width": 1100, "height": 560}


def npm_monaco(folder: Path) -> Path:
    target = folder / "node_modules" / "monaco-editor" / "min"
    if not target.is_dir():
        print(f"npm install {MONACO} into {folder}", flush=True)
        subprocess.run(["npm", "install", "--no-audit", "--no-fund", "--prefix", str(folder), MONACO],
                       check=True)
    return target


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def position(text: str, line_text: str, column_after: str = "") -> tuple[int, int]:
    """1-based (line, column) of the first line containing `line_text`, at the end of
    `column_after` in it (else at the start of `line_text`)."""
    for number, line in enumerate(text.splitlines(), 1):
        if line_text in line:
            start = line.index(line_text)
            return number, start + (len(column_after) if column_after else 0) + 1
    raise ValueError(f"{line_text!r} is not in {SOURCE}")


def wait_listening(port: int, run: subprocess.Popen, timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if run.poll() is not None:
            raise RuntimeError(f"stvm run exited with {run.returncode} before serving OPC UA")
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            return
        except OSError:
            time.sleep(0.5)
    raise RuntimeError(f"nothing listens on 127.0.0.1:{port} after {timeout} s")


class Session:
    """One page of Monaco with its own bridge and `stvm lsp`."""

    def __init__(self, browser, monaco: Path, options: dict) -> None:
        self.http, self.lsp = bridge.start(static=HERE / "static", mounts={"/monaco/": monaco}, cwd=ROOT)
        self.page = browser.new_page(viewport=VIEWPORT)
        self.errors: list[str] = []
        self.page.on("pageerror", lambda exc: self.errors.append(str(exc)))
        self.page.goto(f"http://127.0.0.1:{self.http.server_port}/index.html")
        self.page.wait_for_function("window.monacoReady === true", timeout=60_000)
        self.text = SOURCE.read_text(encoding="utf-8")
        self.page.evaluate("([uri, text, options]) => openFile(uri, text, options)",
                           [SOURCE.as_uri(), self.text, options])
        # the first answer waits for the project's check; a hover request is a cheap way to wait
        self.page.evaluate("() => rpc('textDocument/hover', {textDocument: {uri: editor.getModel().uri.toString()}, "
                           "position: {line: 0, character: 0}})")

    def go(self, line: int, column: int, top: int) -> None:
        self.page.evaluate("([l, c, top]) => { editor.setPosition({lineNumber: l, column: c}); "
                           "editor.setScrollTop(editor.getTopForLineNumber(top)); editor.focus(); }",
                           [line, column, top])

    def action(self, name: str) -> None:
        # editor.trigger runs a command as a keybinding would (the peek actions are not in getAction)
        self.page.evaluate("(name) => editor.trigger('keyboard', name, null)", name)

    def shot(self, out: Path, name: str) -> None:
        time.sleep(0.4)   # let the widget's fade-in finish
        path = out / f"{name}.png"
        self.page.locator("#editor").screenshot(path=str(path))
        print(f"{path}: {path.stat().st_size // 1024} KB", flush=True)

    def close(self) -> None:
        self.page.close()
        bridge.stop(self.http, self.lsp)
        if self.errors:
            raise RuntimeError(f"JavaScript errors on the page: {self.errors}")


def shoot(browser, monaco: Path, out: Path) -> None:
    session = Session(browser, monaco, {"liveValues": {"enable": False}})
    try:
        text = session.text
        line, column = position(text, "CBT_MoveAbsolute_Instance(", "CBT_MoveAbs")
        session.go(line, column, line - 12)
        session.action("editor.action.showHover")
        session.page.locator(".monaco-hover .hover-contents").first.wait_for(state="visible", timeout=30_000)
        session.shot(out, "hover")
        session.page.keyboard.press("Escape")

        # completion: a new line before the call, typed as a user would; `.` triggers it
        session.go(line, 1, line - 12)
        session.page.keyboard.press("Enter")
        session.go(line, 1, line - 12)
        session.page.keyboard.type("    CBT_MoveAbsolute_Instance", delay=20)
        session.page.keyboard.press("Escape")
        session.page.keyboard.type(".", delay=20)
        session.page.locator(".suggest-widget.visible .monaco-list-row").first.wait_for(state="visible", timeout=30_000)
        session.shot(out, "completion")
        session.page.keyboard.press("Escape")
        # back to the file's text (a didChange like any edit)
        session.page.evaluate("(text) => editor.getModel().setValue(text)", text)

        line, column = position(text, "Execute :=MoveExecute", "Execute :=")
        session.go(line, column, line - 12)
        session.action("editor.action.triggerParameterHints")
        session.page.locator(".parameter-hints-widget.visible").first.wait_for(state="visible", timeout=30_000)
        session.shot(out, "signature-help")
        session.page.keyboard.press("Escape")

        # definition: Monaco's peek view shows the declaration the server points to
        line, column = position(text, "IF MoveDone THEN", "IF ")
        session.go(line, column, line - 3)
        session.action("editor.action.peekDefinition")
        session.page.locator(".peekview-widget").first.wait_for(state="visible", timeout=30_000)
        session.shot(out, "definition")
    finally:
        session.close()


def shoot_live(browser, monaco: Path, out: Path) -> None:
    port = free_port()
    endpoint = f"opc.tcp://127.0.0.1:{port}"
    run = subprocess.Popen([sys.executable, "-m", "stvm", "run", str(SOURCE), "--scan", "1ms", "--realtime",
                            "--opcua", endpoint], cwd=ROOT, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
    try:
        wait_listening(port, run)   # compiled, emulator and OPC UA server started
        session = Session(browser, monaco, {"liveValues": {"enable": True, "endpoint": endpoint}})
        try:
            line, _ = position(session.text, "IF PnP_Example_Execute THEN")
            session.go(line, 1, line - 3)
            session.page.locator(".monaco-editor .view-lines [class*='dyn-rule']").first.wait_for(
                state="attached", timeout=60_000)
            time.sleep(3)   # a few refreshes: the values move
            session.shot(out, "live-values")
        finally:
            session.close()
    finally:
        run.terminate()
        run.wait(20)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "editor-screens")
    parser.add_argument("--keep-npm", type=Path, help="install monaco-editor here (kept) instead of a temporary folder")
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright   # lazy: only the screenshot run needs a browser
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        monaco = npm_monaco(args.keep_npm or Path(tmp))
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=FLAGS)
            try:
                shoot(browser, monaco, args.out)
                shoot_live(browser, monaco, args.out)
            finally:
                browser.close()
    print(json.dumps({"out": str(args.out)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
