"""Live values: what a running `stvm run --opcua` (or `stvm debug --opcua`) holds, shown by the
language server as inlay hints beside the variables of the visible lines.

Small on purpose: the running VM already publishes its program and global variables over OPC UA
(stvm/opcua: every variable's string NodeId is its stvm path, `Main.n`, `Cobot.Connected`, in
the namespace `urn:stvm:<project>`), so the editor side is an OPC UA client reading the paths it
shows. The server reads them when the editor asks for inlay hints and, while hints are shown,
polls the same paths every `POLL_SECONDS` and asks the editor to refresh its hints
(`workspace/inlayHint/refresh`) when a value changed — CODESYS's online view, a few times a
second. FB internals are not published by default (the `[opcua] publish` rules), so only the
variables of programs and globals get a value.

The endpoint is `opc.tcp://127.0.0.1:4840` (the `--opcua` default) unless the client's
`initializationOptions.liveValues.endpoint` names another; `liveValues.enable: false` turns the
hints off. Nothing listening there: no hints, and no new attempt for `RETRY_SECONDS`.
"""

from __future__ import annotations

import asyncio
import time

from stvm.semantics import types as t

DEFAULT_ENDPOINT = "opc.tcp://127.0.0.1:4840"
POLL_SECONDS = 0.25
RETRY_SECONDS = 5.0
CONNECT_TIMEOUT = 4.0     # a loaded machine answers an OPC UA handshake slowly; a refused port fails at once


class LiveValues:
    def __init__(self, endpoint: str = DEFAULT_ENDPOINT, enabled: bool = True) -> None:
        self.endpoint = endpoint
        self.enabled = enabled
        self.client = None
        self.ns: int | None = None
        self.failed_at = 0.0
        self.last: dict[str, object] = {}
        self.watched: set[str] = set()
        self.poller: asyncio.Task | None = None

    async def connect(self) -> bool:
        if self.client is not None:
            return True
        if not self.enabled or time.monotonic() - self.failed_at < RETRY_SECONDS:
            return False
        try:
            from asyncua import Client   # lazy: only when live values are asked for
        except ImportError:
            self.enabled = False
            return False
        client = Client(self.endpoint, timeout=CONNECT_TIMEOUT)
        try:
            await asyncio.wait_for(client.connect(), CONNECT_TIMEOUT * 2)
            names = await client.get_namespace_array()
            self.ns = next(i for i, uri in enumerate(names)
                           if uri.startswith("urn:stvm:") and not uri.endswith(":server"))
        except Exception:  # nothing there, not a stvm server, or it went away: no live values
            self.failed_at = time.monotonic()
            try:
                await client.disconnect()
            except Exception:  # already closed
                pass
            return False
        self.client = client
        return True

    async def read(self, paths: list[str]) -> dict[str, object]:
        """{path: value} of the paths the server publishes (the others are left out)."""
        if not paths or not await self.connect():
            return {}
        from asyncua import ua   # lazy: see connect
        params = ua.ReadParameters()
        for path in paths:
            rv = ua.ReadValueId()
            rv.NodeId = ua.NodeId(path, self.ns)
            rv.AttributeId = ua.AttributeIds.Value
            params.NodesToRead.append(rv)
        try:
            results = await self.client.uaclient.read(params)
        except Exception:  # the run ended: forget the connection, try again later
            await self.close()
            self.failed_at = time.monotonic()
            return {}
        out = {}
        for path, result in zip(paths, results):
            if result.StatusCode.is_good() and result.Value is not None:
                out[path] = result.Value.Value
        self.last.update(out)
        return out

    def watch(self, paths: list[str], on_change) -> None:
        """Poll `paths` (the ones the editor shows) and call `on_change()` when a value changes."""
        self.watched = set(paths)
        if self.poller is None or self.poller.done():
            self.poller = asyncio.ensure_future(self._poll(on_change))

    async def _poll(self, on_change) -> None:
        while self.watched and self.client is not None:
            await asyncio.sleep(POLL_SECONDS)
            before = {p: self.last.get(p) for p in self.watched}
            now = await self.read(sorted(self.watched))
            if any(now.get(p) != before.get(p) for p in now):
                await on_change()

    async def close(self) -> None:
        client, self.client = self.client, None
        if client is not None:
            try:
                await client.disconnect()
            except Exception:  # the server is gone already
                pass


def instance_paths(model) -> dict[str, list[str]]:
    """Program key → the instance names the runtime gives it (configured tasks, else the
    program's own name for a program run in the default task)."""
    out: dict[str, list[str]] = {}
    for task in getattr(model, "tasks", ()):
        for instance, qualname in task.programs:
            out.setdefault(qualname.lower(), []).append(instance)
    for qualname in getattr(model, "default_programs", ()):
        out.setdefault(qualname.lower(), []).append(qualname.replace("\\", "."))
    return out


def format_value(value, ty=None) -> str:
    """An IEC literal-like text of an OPC UA value (enumerators by name)."""
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(ty, t.EnumType) and isinstance(value, int):
        name = ty.name_of(value)
        if name is not None:
            return f"{ty.name}#{name}"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, str):
        return "'" + value.replace("'", "$'") + "'"
    text = str(value)
    return text if len(text) <= 40 else text[:39] + "…"
