"""Pages as HTML: one Jinja template (`templates/page.html`), autoescaped, rendered once per page.

The HTML is the black-box contract: every widget carries `data-var` (its ST path), buttons carry
`data-action` (`set:P=V`, `momentary:P`, `preset:NAME`, `page:NAME`, `popup:ID`), lamps
`data-state`. The server renders each page once; live values arrive over the WebSocket.
"""

from __future__ import annotations

import json
from pathlib import Path

import jinja2

from stvm.hmi.pages import Hmi, Page
from stvm.semantics import types as t

TEMPLATES = Path(__file__).resolve().parent / "templates"


class PageRenderer:
    def __init__(self, hmi: Hmi) -> None:
        self.hmi = hmi
        self.env = jinja2.Environment(loader=jinja2.FileSystemLoader(str(TEMPLATES)),
                                      autoescape=True, trim_blocks=True, lstrip_blocks=True,
                                      undefined=jinja2.StrictUndefined)
        self.env.globals["maxlength"] = _maxlength
        self.env.filters["tojson_attr"] = lambda value: json.dumps(value, separators=(",", ":"))
        self._cache: dict[str, str] = {}

    def render(self, page: Page) -> str:
        html = self._cache.get(page.name)
        if html is None:
            nav = [(p.name, p.title) for p in self.hmi.pages.values()]
            html = self.env.get_template("page.html").render(page=page, nav=nav, start=self.hmi.start)
            self._cache[page.name] = html
        return html


def _maxlength(ty) -> int:
    return ty.max_bytes if isinstance(ty, t.StringType) else 524288
