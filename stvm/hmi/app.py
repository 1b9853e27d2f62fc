"""The Starlette routes of the HMI (the contract is in `stvm/hmi/server.py` and docs/hmi.md).

Every answer to a bad request is a 4xx JSON `{"ok": false, "error": reason, "path": …}`; the page
shows `error`. Nothing a client sends can raise out of a handler.
"""

from __future__ import annotations

import asyncio
import json
import secrets
from pathlib import Path
from typing import Any

from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import HTMLResponse, JSONResponse, RedirectResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket, WebSocketDisconnect

from stvm.frontend import WriteRejected
from starlette.requests import ClientDisconnect

from stvm.hmi.wire import SEND_TIMEOUT_S, TOKEN_COOKIE, Client, Refused, is_loopback, json_dumps, token_from

STATIC = Path(__file__).resolve().parent / "static"

# `server` below is the HmiServer (stvm/hmi/server.py), which builds this app: not imported here


def _error(status: int, reason: str, path: str | None = None) -> JSONResponse:
    body = {"ok": False, "error": reason}
    if path is not None:
        body["path"] = path
    return JSONResponse(body, status_code=status)


SECURITY_HEADERS = [
    # clickjacking (issue 34 item 3): no other site may show an HMI page in a frame, where one
    # click of the operator on a disguised page would press a button of the cell
    (b"x-frame-options", b"DENY"),
    (b"content-security-policy", b"frame-ancestors 'none'; default-src 'self'; "
                                 b"style-src 'self' 'unsafe-inline'; img-src 'self' data:; object-src 'none'; "
                                 b"base-uri 'none'; form-action 'self'"),
    (b"x-content-type-options", b"nosniff"),
    (b"referrer-policy", b"no-referrer"),
    (b"cache-control", b"no-store"),
]


class Gate:
    """ASGI middleware in front of every route: the token (when the server has one), the Host
    header of a loopback server (DNS rebinding) and the Origin of writes and WebSockets (another
    site's page in the operator's browser must not drive the cell). Every HTTP answer carries
    `SECURITY_HEADERS`. A client that leaves mid-request ends its handler quietly."""

    def __init__(self, app, server: Any) -> None:
        self.app = app
        self.server = server

    async def __call__(self, scope, receive, send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        if scope["type"] == "http":
            inner_send = send

            async def send(message) -> None:   # noqa: F811 - the same send, with the headers
                if message["type"] == "http.response.start":
                    names = {k.lower() for k, _ in message.get("headers", [])}
                    extra = [(k, v) for k, v in SECURITY_HEADERS if k not in names]
                    message = dict(message, headers=list(message.get("headers", [])) + extra)
                await inner_send(message)
            try:
                await self._gated(scope, receive, send)
            except (OSError, ClientDisconnect):
                pass   # the client went away mid-request: nobody to answer, nothing to log
            return
        await self._gated(scope, receive, send)

    async def _gated(self, scope, receive, send) -> None:
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope.get("headers", [])}
        reason = self._refusal(scope, headers)
        if reason is None:
            await self.app(scope, receive, send)
            return
        status, text = reason
        if scope["type"] == "websocket":
            await send({"type": "websocket.http.response.start", "status": status,
                        "headers": [(b"content-type", b"application/json")]})
            await send({"type": "websocket.http.response.body", "body": json.dumps({"ok": False, "error": text}).encode()})
            return
        await _error(status, text)(scope, receive, send)

    def _refusal(self, scope, headers: dict[str, str]) -> tuple[int, str] | None:
        server = self.server
        host_header = headers.get("host", "")
        if is_loopback(server.host):
            host_name = _host_name(host_header)
            if host_name and not is_loopback(host_name):
                return 403, f"this HMI serves loopback clients only (Host {host_header!r})"
        origin = headers.get("origin")
        if origin and (scope["type"] == "websocket" or scope.get("method") not in ("GET", "HEAD")):
            origin_host = origin.split("://", 1)[-1].rstrip("/")
            if origin_host != host_header:
                return 403, f"cross-origin request from {origin} refused"
        if server.token:
            given = token_from(headers, scope.get("query_string", b"").decode("latin-1"))
            if given is None or not secrets.compare_digest(given.encode(), server.token.encode()):
                return 401, "this HMI needs its token: open the URL printed at start-up (…/?token=…)"
        return None


def build_app(server: Any) -> Starlette:
    hmi = server.hmi

    async def root(request: Request) -> Response:
        response = RedirectResponse(f"/page/{hmi.start}", status_code=302)
        _remember_token(request, response)
        return response

    async def page(request: Request) -> Response:
        name = request.path_params["name"]
        found = hmi.pages.get(name)
        if found is None:
            return HTMLResponse(f"<!doctype html><title>no page</title><p>No HMI page named "
                                f"{_escape(name)}. <a href='/'>Main</a></p>", status_code=404)
        response = HTMLResponse(server.renderer.render(found))
        _remember_token(request, response)
        return response

    async def get_vars(request: Request) -> Response:
        paths = request.query_params.getlist("path")
        if not paths:
            return _error(400, "give the variables as ?path=NAME&path=NAME")
        if len(paths) > 512:
            return _error(413, "too many paths in one read")
        published = set(hmi.paths)
        for path in paths:
            if path not in published:
                if path in hmi.types:
                    continue
                try:
                    server.bridge.type_of(path)
                except Exception:   # noqa: BLE001 - PathError and friends: an unknown path
                    return _error(404, f"{path}: unknown variable", path)
                return _error(403, f"{path}: not shown by any HMI page", path)
        got = await server.read_now(paths)
        if got is None:
            return _error(503, "the VM did not complete a scan in time (stopped in the debugger?)")
        values, scan = got
        return JSONResponse({p: server.bridge.format(p, values[p]) if values[p] is not None else None
                             for p in paths}, headers={"X-Stvm-Scan": str(scan)})

    async def post_vars(request: Request) -> Response:
        try:
            body = await _json_body(request, server.limits)
            values, literals = server.check_writes(body)
            refused = await server.guard_problem(values)
            if refused:
                raise Refused(409, refused)
            scan = await server.submit(values)
            server.notify_write(request.headers.get("x-hmi-client"), literals)
        except Refused as exc:
            return _error(exc.status, exc.reason, exc.path)
        except WriteRejected as exc:
            return _error(503 if exc.path is None else 422, str(exc), exc.path)
        if scan is None:
            return JSONResponse({"ok": True, "queued": True, "written": literals}, status_code=202)
        return JSONResponse({"ok": True, "scan": scan, "written": literals})

    async def post_preset(request: Request) -> Response:
        name = request.path_params["name"]
        try:
            await _json_body(request, server.limits, allow_empty=True)
            steps = server.preset_steps(name)
            scan = None
            for values in steps:
                scan = await server.submit(values)
                if scan is None:
                    return _error(503, f"preset {name}: the VM did not scan in time; "
                                       f"{len(steps)} step(s) not all applied")
        except Refused as exc:
            return _error(exc.status, exc.reason, exc.path)
        except WriteRejected as exc:
            return _error(409, f"preset {name}: {exc}", exc.path)
        return JSONResponse({"ok": True, "scan": scan, "steps": len(steps)})

    async def pages(request: Request) -> Response:
        return JSONResponse({
            "start": hmi.start,
            "pages": {p.name: {"title": p.title, "paths": list(p.paths)} for p in hmi.pages.values()},
            "presets": {n: {"label": p.label, "page": p.page} for n, p in hmi.presets.items()},
            "writable": sorted(p for p in hmi.writable if server.limit_table.limits_for(p).writable),
        })

    async def alarms_page(request: Request) -> Response:
        response = HTMLResponse(server.renderer.render_alarms())
        _remember_token(request, response)
        return response

    async def get_alarms(request: Request) -> Response:
        history = server.alarms.history() if server.alarms is not None else []
        return JSONResponse(dict(server.alarm_json(), history=[a.as_json() for a in history[:100]],
                                 vm=server.vm_state))

    async def ack_alarm(request: Request) -> Response:
        try:
            await _json_body(request, server.limits, allow_empty=True)
        except Refused as exc:
            return _error(exc.status, exc.reason)
        which = request.path_params["which"]
        if server.alarms is None:
            return _error(404, "no alarm list")
        if which == "all":
            count = server.alarms.acknowledge_all()
        elif which.isdigit() and len(which) < 12:
            if server.alarms.acknowledge(int(which)) is None:
                return _error(404, f"no current alarm {which}")
            count = 1
        else:
            return _error(404, f"no current alarm {which}")
        server.send_status(force=True)
        return JSONResponse({"ok": True, "acknowledged": count})

    async def websocket(ws: WebSocket) -> None:
        name = ws.query_params.get("page", hmi.start)
        found = hmi.pages.get(name) or (server.renderer.alarm_page if name == "@alarms" else None)
        if found is None or len(server.clients) >= server.limits.max_websockets:
            await ws.close(code=1008 if found is None else 1013)
            return
        await ws.accept()
        client = Client(ws, found, ws.query_params.get("client", ""))
        server.clients.add(client)
        server._update_watch()
        # rides on the first message (every value of the page); the heartbeat sends it anyway
        client.offer_status(server.check_vm(), server.alarm_json(), wake=False)
        sender = asyncio.create_task(_send_loop(server, client))
        try:
            while True:   # a page only says which pop-up is open; reading also notices it leave
                message = await ws.receive()
                if message["type"] == "websocket.disconnect":
                    break
                popup = _popup_request(message.get("text"))
                if popup is not False and client.open_popup(popup):
                    server._update_watch()
                    client.offer(server, {}, None, [])   # what is known now; the rest follows
        except (WebSocketDisconnect, RuntimeError, OSError):
            pass
        finally:
            sender.cancel()
            await asyncio.gather(sender, return_exceptions=True)
            server.clients.discard(client)
            server._update_watch()

    async def not_found(request: Request, exc) -> Response:
        return _error(404, f"no such resource: {request.url.path}")

    async def method_not_allowed(request: Request, exc) -> Response:
        return _error(405, f"{request.method} is not allowed on {request.url.path}")

    routes = [
        Route("/", root),
        Route("/page/{name}", page),
        Route("/api/vars", get_vars, methods=["GET"]),
        Route("/api/vars", post_vars, methods=["POST"]),
        Route("/api/presets/{name}", post_preset, methods=["POST"]),
        Route("/api/pages", pages),
        Route("/alarms", alarms_page),
        Route("/api/alarms", get_alarms, methods=["GET"]),
        Route("/api/alarms/{which}/ack", ack_alarm, methods=["POST"]),
        WebSocketRoute("/ws", websocket),
        Mount("/static", StaticFiles(directory=str(STATIC)), name="static"),
    ]
    app = Starlette(routes=routes, exception_handlers={404: not_found, 405: method_not_allowed})
    return Gate(app, server)


async def _send_loop(server: Any, client: Client) -> None:
    ws = client.websocket
    try:
        while True:
            await client.wake.wait()
            client.wake.clear()
            message = client.take()
            async with asyncio.timeout(SEND_TIMEOUT_S):   # (not wait_for: no task per message)
                await ws.send_text(json_dumps(message))
    except asyncio.CancelledError:
        raise
    except Exception:   # noqa: BLE001 - a vanished or stalled client: drop it, never the server
        server.stats["dropped_clients"] += 1
        server.clients.discard(client)
        server._update_watch()
        try:
            await ws.close(code=1011)
        except Exception:   # noqa: BLE001
            pass


def _popup_request(text: str | None):
    """`{"popup": "Segment-1"}` / `{"popup": null}` → the id / None; anything else → False."""
    if not text or len(text) > 200:
        return False
    try:
        data = json.loads(text)
    except ValueError:
        return False
    if not isinstance(data, dict) or "popup" not in data:
        return False
    popup = data["popup"]
    return popup if popup is None or isinstance(popup, str) else False


async def _json_body(request: Request, limits, allow_empty: bool = False):
    """The request's JSON, refused with 415/413/400 (type, size, syntax, nesting) before anything
    runs. A client that leaves mid-body raises ClientDisconnect (the Gate ends the request)."""
    max_body = limits.max_body_bytes
    ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
    length = request.headers.get("content-length")
    if length is not None:
        if not length.isdigit():
            raise Refused(400, "bad Content-Length")
        if int(length) > max_body:
            raise Refused(413, f"body too large ({length} bytes > {max_body})")
    chunks = []
    size = 0
    async for chunk in request.stream():
        size += len(chunk)
        if size > max_body:
            raise Refused(413, f"body too large (> {max_body} bytes)")
        chunks.append(chunk)
    raw = b"".join(chunks)
    if not raw.strip():
        if allow_empty:
            return {}
        raise Refused(400, "empty body: send a JSON object {\"<variable path>\": \"<IEC literal>\"}")
    if ctype != "application/json":
        raise Refused(415, "send the body as Content-Type: application/json")
    depth = _json_depth(raw)
    if depth > limits.max_json_depth:
        # refused before parsing: json.loads would recurse once per level (RecursionError)
        raise Refused(400, f"JSON nested too deeply ({depth} levels > {limits.max_json_depth})")
    try:
        return json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise Refused(400, f"malformed JSON: {exc}") from None


def _json_depth(raw: bytes) -> int:
    """The deepest nesting of [ and { outside strings (a linear scan, no recursion)."""
    depth = deepest = 0
    in_string = escaped = False
    for byte in raw:
        if in_string:
            if escaped:
                escaped = False
            elif byte == 0x5C:      # backslash
                escaped = True
            elif byte == 0x22:      # "
                in_string = False
        elif byte == 0x22:
            in_string = True
        elif byte in (0x5B, 0x7B):  # [ {
            depth += 1
            if depth > deepest:
                deepest = depth
        elif byte in (0x5D, 0x7D):
            depth -= 1
    return deepest


def _remember_token(request: Request, response: Response) -> None:
    token = request.query_params.get("token")
    if token:
        response.set_cookie(TOKEN_COOKIE, token, httponly=True, samesite="strict")


def _host_name(header: str) -> str:
    """The host part of a Host header (`127.0.0.1:8080`, `[::1]:8080`, `localhost`)."""
    if header.startswith("["):
        return header[1:header.find("]")] if "]" in header else header
    return header.rsplit(":", 1)[0] if header.count(":") == 1 else header


def _escape(text: str) -> str:
    import html
    return html.escape(text)
