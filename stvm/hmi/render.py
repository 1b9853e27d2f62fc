"""Pages as HTML: one Jinja template (`templates/page.html`), autoescaped, rendered once per page.

The HTML is the black-box contract: every widget carries `data-var` (its ST path), buttons carry
`data-action` (`set:P=V`, `momentary:P`, `preset:NAME`, `page:NAME`, `popup:ID`), lamps
`data-state`. The server renders each page once; live values arrive over the WebSocket.
"""

from __future__ import annotations

import json
from pathlib import Path

import jinja2

from stvm.hmi.pages import Area, Hmi, Page
from stvm.semantics import types as t

ALARM_PAGE = Page("@alarms", "Alarms", "", (), ())
"""The alarm list (`/alarms`): a page of no variables; the list arrives over the WebSocket."""

_SIDE_KINDS = {"lamp", "status", "toggle", "momentary", "set", "nav"}

TEMPLATES = Path(__file__).resolve().parent / "templates"


class PageRenderer:
    alarm_page = ALARM_PAGE

    def __init__(self, hmi: Hmi, limit_table=None) -> None:
        self.hmi = hmi
        self.limit_table = limit_table
        self.env = jinja2.Environment(loader=jinja2.FileSystemLoader(str(TEMPLATES)),
                                      autoescape=True, trim_blocks=True, lstrip_blocks=True,
                                      undefined=jinja2.StrictUndefined)
        self.env.globals["maxlength"] = _maxlength
        self.env.globals["limits"] = self._limits
        self.env.globals["meaning"] = _meaning
        self.env.globals["role"] = area_role
        self.env.globals["dict"] = dict
        self.env.globals["is_text"] = lambda ty: isinstance(ty, (t.StringType, t.TimeType))
        self.env.filters["tojson_attr"] = lambda value: json.dumps(value, separators=(",", ":"))
        self._cache: dict[str, str] = {}

    def render(self, page: Page) -> str:
        html = self._cache.get(page.name)
        if html is None:
            nav = [(p.name, p.title) for p in self.hmi.pages.values()]
            html = self.env.get_template("page.html").render(page=page, nav=nav, start=self.hmi.start,
                                                             alarm_list=False)
            self._cache[page.name] = html
        return html

    def render_alarms(self) -> str:
        html = self._cache.get("@alarms")
        if html is None:
            nav = [(p.name, p.title) for p in self.hmi.pages.values()]
            html = self.env.get_template("page.html").render(page=ALARM_PAGE, nav=nav, start=self.hmi.start,
                                                             alarm_list=True)
            self._cache["@alarms"] = html
        return html

    def _limits(self, path: str | None):
        if path is None or self.limit_table is None:
            return None
        return self.limit_table.limits_for(path)


def area_role(area: Area) -> str:
    """`side`: commands and their status (kept in view while parameters are edited, docs/hmi.md
    "Panel layout"); `edit`: everything else."""
    if area.place:
        return "side" if area.place == "side" else "edit"
    kinds = {w.kind for w in area.widgets}
    if kinds & {"numeric", "dropdown", "text", "robot_view", "popup"}:
        return "edit"
    return "side" if kinds & _SIDE_KINDS else "edit"


def _meaning(widget) -> str:
    """A lamp's colour by meaning: the page's `meaning`, else from its name (Error → error,
    Busy/WaitingReturn → warning, anything else → ok)."""
    explicit = getattr(widget, "meaning", "")
    if explicit:
        return explicit
    name = f"{widget.var or ''} {widget.label}".lower()
    if "error" in name or "fault" in name or "lost" in name:
        return "error"
    if "busy" in name or "waiting" in name or "warn" in name or "pause" in name:
        return "warning"
    return "ok"


def _maxlength(ty) -> int:
    return ty.max_bytes if isinstance(ty, t.StringType) else 524288
