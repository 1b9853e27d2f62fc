"""HMI page files (TOML) → a checked, plain-data `Hmi`: what every page shows and may write.

The format is documented in docs/hmi.md; in short, one file per page::

    [page]
    name = "pgConnect"                  # the URL is /page/pgConnect
    title = "Connect"

    [[area]]                            # a framed group of widgets, drawn in order
    title = "Connection Settings"

    [[area.widget]]
    kind = "text"                       # lamp numeric dropdown text status toggle momentary set
    var = "Connect_AddressIP"           #   preset nav popup robot_view note
    label = "Robot IP"

    [[preset]]                          # values written together by a preset button
    name = "ConnectDefaults"
    label = "Preset Values"
    [preset.values]
    Connect_Time_Out = 100

Like an NA HMI's variable mapping, the files name ST variables by the path `stvm run --print`
accepts; `load_pages` checks every path against the running VM (it exists, is elementary, has a
type the widget can show), every limit (min ≤ max, inside the type) and every preset value, and
reports each mistake as `FILE:LINE:COL: error: message` (a `Diagnostic`), never a traceback.
"""

from __future__ import annotations

import math

import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

from stvm.diagnostics import Diagnostic
from stvm.hmi.tomlpos import TomlLocator
from stvm.semantics import types as t
from stvm.semantics.literals import literal_value
from stvm.syntax.nodes import Span
from stvm.syntax.literals import decode_int
from stvm.diagnostics import render
from stvm.runtime.vm import coerce_python_value

MAX_PAGE_FILE_BYTES = 1 << 20
"""A page file larger than this is refused (the limits file has the same bound)."""
MAX_LIMIT = 1e18
"""A page's min/max beyond this is refused: no ST number an operator types is larger (LREAL's
range aside, a position or speed of 1e18 is a typing mistake)."""

WIDGET_KINDS = ("lamp", "numeric", "dropdown", "text", "status", "toggle", "momentary", "set",
                "preset", "nav", "popup", "robot_view", "note")
WRITING_KINDS = ("numeric", "dropdown", "text", "toggle", "momentary", "set")

_COMMON = {"kind", "label"}
_KEYS: dict[str, set[str]] = {
    "lamp": {"var", "meaning"},
    "numeric": {"var", "min", "max", "unit", "step"},
    "dropdown": {"var", "options"},
    "text": {"var"},
    "status": {"var", "unit"},
    "toggle": {"var"},
    "momentary": {"var"},
    "set": {"var", "value"},
    "preset": {"preset"},
    "nav": {"page"},
    "popup": {"popup", "instance"},
    "robot_view": {"targets", "history_s", "x_range", "y_range", "z_range", "views"},
    "note": set(),
}
RUN_PARAMETERS = ("robot_host", "robot_port")
"""Values a preset may take from the run (`{ run = "robot_port" }`): the robot the run talks to."""

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
DEFAULT_RANGES = {"x_range": (-800.0, 800.0), "y_range": (-800.0, 800.0), "z_range": (-200.0, 1000.0)}


class HmiLoadError(Exception):
    """The page files have errors; `diagnostics` holds all of them, `sources` their texts."""

    def __init__(self, diagnostics: list[Diagnostic], sources: dict[str, str]) -> None:
        super().__init__(f"{len(diagnostics)} error(s) in HMI pages")
        self.diagnostics = diagnostics
        self.sources = sources

    def render(self) -> str:
        return "".join(render(d, self.sources) for d in self.diagnostics)


@dataclass(frozen=True)
class Limits:
    """What a write to one variable must satisfy (the strictest of every widget that maps it)."""

    type: t.Type
    min: float | None = None
    max: float | None = None
    options: tuple[int, ...] | None = None   # a drop-down over an integer: the allowed values
    by: tuple[str, ...] = ()                 # "pgMoveAbsolute: Speed", for messages


@dataclass(frozen=True)
class Widget:
    kind: str
    label: str = ""
    var: str | None = None           # the ST path, for every kind that shows or writes a variable
    type: t.Type | None = field(default=None, compare=False)
    unit: str = ""
    min: float | None = None
    max: float | None = None
    step: str = "any"
    options: tuple[tuple[str, str], ...] = ()   # drop-down: (shown text, IEC literal)
    value: str | None = None                    # set: the IEC literal written
    target: str | None = None                   # preset name, page name or popup instance id
    targets: tuple[str, ...] = ()               # robot_view: struct paths with X, Y, Z
    history_s: float = 20.0
    ranges: tuple[tuple[float, float], ...] = ()  # robot_view: x, y, z ranges in mm
    views: tuple[str, ...] = ("XY", "XZ")         # robot_view: the projections drawn (axes →, ↑)
    meaning: str = ""                             # lamp: error | warning | ok (colour); "": by name


@dataclass(frozen=True)
class Area:
    title: str
    widgets: tuple[Widget, ...]
    place: str = ""                  # "side" (commands, status) | "main" | "": by its widgets


@dataclass(frozen=True)
class Popup:
    id: str                          # "<name>-<instance>", the target of `popup:` actions
    title: str
    widgets: tuple[Widget, ...]


@dataclass(frozen=True)
class Preset:
    name: str
    label: str
    page: str
    steps: tuple[tuple[tuple[str, Any], ...], ...]   # batches of (path, value or RunParameter)


@dataclass(frozen=True)
class RunParameter:
    name: str


@dataclass(frozen=True)
class Page:
    name: str
    title: str
    file: str
    areas: tuple[Area, ...]
    popups: tuple[Popup, ...]

    def widgets(self):
        for area in self.areas:
            yield from area.widgets
        for popup in self.popups:
            yield from popup.widgets

    @property
    def paths(self) -> tuple[str, ...]:
        """Every variable this page shows, in page order, each once (robot-view targets too)."""
        return _paths(self.widgets())

    @property
    def base_paths(self) -> tuple[str, ...]:
        """What the page shows with no pop-up open (a pop-up's fields are watched while open)."""
        return _paths(w for area in self.areas for w in area.widgets)

    def popup_paths(self, popup_id: str) -> tuple[str, ...]:
        return _paths(w for p in self.popups if p.id == popup_id for w in p.widgets)

    @property
    def has_robot_view(self) -> bool:
        return any(w.kind == "robot_view" for w in self.widgets())


@dataclass(frozen=True)
class Guard:
    """A write a page refuses while other variables are all zero (`[[guard]]`, docs/hmi.md)."""

    var: str
    value: Any                      # the Python value whose write is refused (TRUE: an Execute)
    all_zero: tuple[str, ...]
    message: str


@dataclass(frozen=True)
class Hmi:
    pages: Mapping[str, Page]
    presets: Mapping[str, Preset]
    writable: Mapping[str, Limits]
    start: str
    types: Mapping[str, t.Type] = field(compare=False, default_factory=dict)
    guards: Mapping[str, tuple[Guard, ...]] = field(compare=False, default_factory=dict)

    @property
    def paths(self) -> tuple[str, ...]:
        seen: dict[str, None] = {}
        for page in self.pages.values():
            for path in page.paths:
                seen[path] = None
        return tuple(seen)


# ---------------------------------------------------------------------------------------------

class _File:
    """One page file being read: its text, locator and the diagnostics found in it."""

    def __init__(self, path: str, text: str, diags: list[Diagnostic]) -> None:
        self.path = path
        self.text = text
        self.locator = TomlLocator(text)
        self.diags = diags

    def error(self, where: tuple, message: str) -> None:
        line, column = self.locator.locate(where)
        self.diags.append(Diagnostic.error(message, Span(self.path, line, column, line, column + 1)))


def load_pages(files: Sequence[str | Path], type_of: Callable[[str], t.Type],
               start: str | None = None) -> Hmi:
    """Read and check the page files. `type_of(path)` gives a variable's ST type or raises
    (`KeyError`/`ValueError`, e.g. `stvm.runtime.vm.PathError`) for an unknown path. Raises
    `HmiLoadError` with every problem found."""
    diags: list[Diagnostic] = []
    sources: dict[str, str] = {}
    reader = _Reader(type_of, diags)
    for raw in files:
        path = str(raw)
        try:
            with open(path, "rb") as fh:   # bounded: /dev/zero or a huge file is refused, not read whole
                data = fh.read(MAX_PAGE_FILE_BYTES + 1)
            if len(data) > MAX_PAGE_FILE_BYTES:
                diags.append(Diagnostic.error(f"HMI page file larger than {MAX_PAGE_FILE_BYTES} bytes",
                                              Span(path, 1, 1, 1, 2)))
                continue
            text = data.decode("utf-8")
        except OSError as exc:
            diags.append(Diagnostic.error(f"cannot read HMI page file: {exc.strerror or exc}",
                                          Span(path, 1, 1, 1, 2)))
            continue
        except UnicodeDecodeError:
            diags.append(Diagnostic.error("HMI page file is not UTF-8 text", Span(path, 1, 1, 1, 2)))
            continue
        sources[path] = text
        reader.read_file(_File(path, text, diags))
    reader.check_references()
    if diags:
        raise HmiLoadError(diags, sources)
    if start is None:
        start = "Main" if "Main" in reader.pages else next(iter(reader.pages), "Main")
    elif start not in reader.pages:
        raise HmiLoadError([Diagnostic.error(f"start page {start!r} is not one of the pages "
                                             f"({', '.join(reader.pages) or 'none'})",
                                             Span(str(files[0]) if files else "<hmi>", 1, 1, 1, 2))], sources)
    return Hmi(reader.pages, reader.presets, reader.limits(), start, reader.types,
               {k: tuple(v) for k, v in reader.guards.items()})


class _Reader:
    def __init__(self, type_of: Callable[[str], t.Type], diags: list[Diagnostic]) -> None:
        self.type_of = type_of
        self.diags = diags
        self.pages: dict[str, Page] = {}
        self.presets: dict[str, Preset] = {}
        self.types: dict[str, t.Type] = {}
        self._limits: dict[str, list[tuple[Widget, str]]] = {}
        # references checked once every file is read: (file, where, kind, name)
        self._refs: list[tuple[_File, tuple, str, str]] = []
        self._popups: dict[str, set[str]] = {}   # page → popup ids
        self._preset_checks: list[tuple[_File, tuple, str, Any]] = []
        self.guards: dict[str, list[Guard]] = {}

    # ---- files
    def read_file(self, f: _File) -> None:
        try:
            data = tomllib.loads(f.text)
        except tomllib.TOMLDecodeError as exc:
            message = str(exc)
            m = re.search(r"\(at line (\d+), column (\d+)\)", message)
            line, column = (int(m.group(1)), int(m.group(2))) if m else (1, 1)
            text = re.sub(r"\s*\(at line \d+, column \d+\)", "", message) if m else message
            f.diags.append(Diagnostic.error(f"TOML syntax: {text}", Span(f.path, line, column, line, column + 1)))
            return
        self._known(f, (), data, {"page", "area", "popup", "preset", "guard"}, "a page file")
        page_table = data.get("page")
        if not isinstance(page_table, dict):
            f.error((), "a page file needs a [page] table with name = \"...\"")
            return
        self._known(f, ("page",), page_table, {"name", "title"}, "[page]")
        name = page_table.get("name")
        if not isinstance(name, str) or not _NAME.match(name):
            f.error(("page", "name"), "page name must be a name (letters, digits, _), e.g. \"pgConnect\"")
            return
        if name in self.pages:
            f.error(("page", "name"), f"page {name!r} is defined twice (also in {self.pages[name].file})")
            return
        title = self._string(f, ("page", "title"), page_table.get("title", name))
        popups = self._read_popups(f, name, data.get("popup", []))
        areas = []
        for i, area in enumerate(self._tables(f, ("area",), data.get("area", []), "[[area]]")):
            self._known(f, ("area", i), area, {"title", "widget", "place"}, "[[area]]")
            widgets = self._read_widgets(f, ("area", i, "widget"), area.get("widget", []), name, {})
            place = area.get("place", "")
            if place not in ("", "side", "main"):
                f.error(("area", i, "place"), "place must be \"side\" (beside every tab) or \"main\" (a tab)")
                place = ""
            areas.append(Area(self._string(f, ("area", i, "title"), area.get("title", "")), tuple(widgets), place))
        for i, preset in enumerate(self._tables(f, ("preset",), data.get("preset", []), "[[preset]]")):
            self._read_preset(f, ("preset", i), preset, name)
        for i, guard in enumerate(self._tables(f, ("guard",), data.get("guard", []), "[[guard]]")):
            self._read_guard(f, ("guard", i), guard)
        self.pages[name] = Page(name, title, f.path, tuple(areas), tuple(popups))

    def _read_guard(self, f: _File, where: tuple, table: dict) -> None:
        if not self._known(f, where, table, {"var", "value", "all_zero", "message"}, "[[guard]]"):
            return
        var, ty = self._variable(f, where + ("var",), table.get("var"), {}, "")
        if var is None:
            return
        literal = self._literal(f, where + ("value",), var, ty, table.get("value", True), "")
        zero = table.get("all_zero")
        message = table.get("message")
        if not isinstance(zero, list) or not zero or not all(isinstance(x, str) for x in zero):
            f.error(where + ("all_zero",), "all_zero must be a list of variable paths")
            return
        if not isinstance(message, str) or not message.strip():
            f.error(where + ("message",), "a guard needs message = \"<what the operator is told>\"")
            return
        paths = []
        for path in zero:
            checked, _ = self._variable(f, where + ("all_zero",), path, {}, "")
            if checked is None:
                return
            paths.append(checked)
        if literal is None:
            return
        value = coerce_python_value(literal_value(literal, ty), ty)
        self.guards.setdefault(var, []).append(Guard(var, value, tuple(paths), message.strip()))

    def _read_popups(self, f: _File, page: str, raw: Any) -> list[Popup]:
        popups: list[Popup] = []
        ids = self._popups.setdefault(page, set())
        for i, popup in enumerate(self._tables(f, ("popup",), raw, "[[popup]]")):
            where = ("popup", i)
            self._known(f, where, popup, {"name", "title", "instances", "widget"}, "[[popup]]")
            name = popup.get("name")
            if not isinstance(name, str) or not _NAME.match(name):
                f.error(where + ("name",), "popup name must be a name (letters, digits, _)")
                continue
            instances = popup.get("instances", [""])
            if not isinstance(instances, list) or not instances or \
                    not all(isinstance(x, (int, str)) and not isinstance(x, bool) for x in instances):
                f.error(where + ("instances",), "instances must be a non-empty list of integers or strings")
                continue
            for instance in instances:
                subst = {"n": str(instance)}
                popup_id = f"{name}-{instance}" if instance != "" else name
                if popup_id in ids:
                    f.error(where + ("name",), f"popup {popup_id!r} is defined twice on page {page}")
                    continue
                ids.add(popup_id)
                widgets = self._read_widgets(f, where + ("widget",), popup.get("widget", []), page, subst)
                title = _substitute(self._string(f, where + ("title",), popup.get("title", name)), subst)
                popups.append(Popup(popup_id, title, tuple(widgets)))
        return popups

    # ---- widgets
    def _read_widgets(self, f: _File, where: tuple, raw: Any, page: str, subst: dict[str, str]) -> list[Widget]:
        widgets = []
        for i, table in enumerate(self._tables(f, where, raw, "[[…widget]]")):
            widget = self._read_widget(f, where + (i,), table, page, subst)
            if widget is not None:
                widgets.append(widget)
        return widgets

    def _read_widget(self, f: _File, where: tuple, table: dict, page: str, subst: dict[str, str]) -> Widget | None:
        kind = table.get("kind")
        if kind not in WIDGET_KINDS:
            f.error(where + ("kind",), f"unknown widget kind {kind!r} (kinds: {', '.join(WIDGET_KINDS)})"
                    if kind is not None else f"a widget needs kind = one of {', '.join(WIDGET_KINDS)}")
            return None
        if not self._known(f, where, table, _COMMON | _KEYS[kind], f"a {kind} widget"):
            return None
        label = _substitute(self._string(f, where + ("label",), table.get("label", "")), subst)
        context = f" (popup instance {subst['n']})" if subst.get("n") else ""
        var = ty = None
        if "var" in _KEYS[kind]:
            var, ty = self._variable(f, where + ("var",), table.get("var"), subst, context)
            if var is None:
                return None
            if not self._kind_fits(f, where, kind, var, ty, context):
                return None
        widget = Widget(kind, label, var, ty)
        fields: dict[str, Any] = {}
        if kind == "numeric":
            fields.update(self._numeric(f, where, table, ty, var, context))
            if fields.get("invalid"):
                return None
            fields.pop("invalid", None)
        elif kind == "status":
            fields["unit"] = self._string(f, where + ("unit",), table.get("unit", ""))
        elif kind == "lamp" and "meaning" in table:
            meaning = table["meaning"]
            if meaning not in ("error", "warning", "ok", "neutral"):
                f.error(where + ("meaning",), "meaning must be \"error\", \"warning\", \"ok\" or \"neutral\"")
                return None
            fields["meaning"] = meaning
        elif kind == "dropdown":
            options = self._options(f, where + ("options",), table.get("options"), ty, var)
            if options is None:
                return None
            fields["options"] = options
        elif kind == "set":
            raw = table.get("value")
            if raw is None:
                f.error(where, f"a set button needs value = the literal written to {var}")
                return None
            literal = self._literal(f, where + ("value",), var, ty, raw, context)
            if literal is None:
                return None
            fields["value"] = literal
        elif kind in ("preset", "nav"):
            key = kind if kind == "preset" else "page"
            name = table.get(key)
            if not isinstance(name, str):
                f.error(where + (key,), f"a {kind} button needs {key} = \"<name>\"")
                return None
            fields["target"] = name
            self._refs.append((f, where + (key,), kind, name))
        elif kind == "popup":
            name = table.get("popup")
            if not isinstance(name, str):
                f.error(where + ("popup",), "a popup button needs popup = \"<popup name>\"")
                return None
            instance = table.get("instance", "")
            target = f"{name}-{instance}" if instance != "" else name
            fields["target"] = target
            self._refs.append((f, where + ("popup",), "popup:" + page, target))
        elif kind == "robot_view":
            view = self._robot_view(f, where, table, subst)
            if view is None:
                return None
            fields.update(view)
        if not label and kind in ("toggle", "momentary", "set", "preset", "nav", "popup", "note"):
            fields["label"] = fields.get("target") or var or kind
        widget = Widget(**{**widget.__dict__, **fields})
        if kind in WRITING_KINDS:
            self._limits.setdefault(var, []).append((widget, page))
        return widget

    def _variable(self, f: _File, where: tuple, raw: Any, subst: dict[str, str], context: str):
        if not isinstance(raw, str) or not raw.strip():
            f.error(where, "var must be the path of an ST variable, e.g. \"MoveAbs_Param.Speed\"")
            return None, None
        path = _substitute(raw.strip(), subst)
        try:
            ty = self.type_of(path)
        except (KeyError, ValueError, LookupError) as exc:
            f.error(where, f"unknown variable path {path!r}{context}: {_reason(exc)}")
            return None, None
        if isinstance(ty, (t.StructType, t.ArrayType, t.FBType)):
            f.error(where, f"{path} is a {ty.name}{context}: map its elementary members "
                           f"(e.g. {path}{'[…]' if isinstance(ty, t.ArrayType) else '.<member>'})")
            return None, None
        self.types[path] = ty
        return path, ty

    def _kind_fits(self, f: _File, where: tuple, kind: str, var: str, ty: t.Type, context: str) -> bool:
        ok = {
            "lamp": isinstance(ty, t.BoolType),
            "toggle": isinstance(ty, t.BoolType),
            "momentary": isinstance(ty, t.BoolType),
            "numeric": isinstance(ty, (t.IntType, t.RealType)),
            "dropdown": isinstance(ty, (t.EnumType, t.IntType, t.BoolType)),
            "text": isinstance(ty, t.StringType),
        }.get(kind, True)
        if not ok:
            wanted = {"lamp": "a BOOL", "toggle": "a BOOL", "momentary": "a BOOL", "numeric": "an integer or REAL",
                      "dropdown": "an enumeration, integer or BOOL", "text": "a STRING"}[kind]
            f.error(where + ("var",), f"wrong type: a {kind} widget needs {wanted} variable, "
                                      f"{var} is {ty.name}{context}")
        return ok

    def _numeric(self, f: _File, where: tuple, table: dict, ty: t.Type, var: str, context: str) -> dict:
        out: dict[str, Any] = {"unit": self._string(f, where + ("unit",), table.get("unit", ""))}
        bounds = {}
        for key in ("min", "max"):
            if key not in table:
                continue
            value = table[key]
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                f.error(where + (key,), f"{key} must be a number, got {value!r}")
                out["invalid"] = True
                continue
            # nan/inf (TOML spells them) and numbers beyond any ST type are no limit (float(nan)
            # != int(nan) raised ValueError: exit 70)
            if not math.isfinite(value) or abs(value) > MAX_LIMIT:
                f.error(where + (key,), f"{key} must be a finite number within ±{MAX_LIMIT:g}, got {value!r}")
                out["invalid"] = True
                continue
            if isinstance(ty, t.IntType):
                if float(value) != int(value):
                    f.error(where + (key,), f"{key} must be an integer for {var} ({ty.name}), got {value!r}")
                    out["invalid"] = True
                    continue
                if not ty.lo <= value <= ty.hi:
                    f.error(where + (key,), f"{key} {value} is outside {ty.name} ({ty.lo}..{ty.hi})")
                    out["invalid"] = True
                    continue
                value = int(value)
            bounds[key] = value
        if "min" in bounds and "max" in bounds and bounds["min"] > bounds["max"]:
            f.error(where + ("max",), f"min {bounds['min']} is greater than max {bounds['max']}{context}")
            out["invalid"] = True
        out.update(bounds)
        step = table.get("step")
        if step is not None:
            if isinstance(step, bool) or not isinstance(step, (int, float)) or step <= 0:
                f.error(where + ("step",), f"step must be a positive number, got {step!r}")
                out["invalid"] = True
            else:
                out["step"] = str(step)
        elif isinstance(ty, t.IntType):
            out["step"] = "1"
        return out

    def _options(self, f: _File, where: tuple, raw: Any, ty: t.Type, var: str):
        if isinstance(ty, t.EnumType):
            names = [name for name, _ in ty.members]
            if raw is None:
                return tuple((name, name) for name in names)
            if not isinstance(raw, list) or not all(isinstance(x, str) for x in raw):
                f.error(where, f"options of an enumeration drop-down are a list of its names ({', '.join(names)})")
                return None
            out = []
            for item in raw:
                member = next((n for n in names if n.lower() == item.lower()), None)
                if member is None:
                    f.error(where, f"{item!r} is not a value of {ty.name} ({', '.join(names)})")
                    return None
                out.append((member, member))
            return tuple(out)
        if isinstance(ty, t.BoolType) and raw is None:
            return (("FALSE", "FALSE"), ("TRUE", "TRUE"))
        if not isinstance(raw, dict) or not raw:
            f.error(where, f"a drop-down over {var} ({ty.name}) needs options = {{ NAME = value, … }}")
            return None
        out = []
        for text, value in raw.items():
            literal = self._literal(f, where + (text,), var, ty, value, "")
            if literal is None:
                return None
            out.append((text, literal))
        return tuple(out)

    def _robot_view(self, f: _File, where: tuple, table: dict, subst: dict[str, str]) -> dict | None:
        out: dict[str, Any] = {}
        targets = table.get("targets", [])
        if not isinstance(targets, list) or not all(isinstance(x, str) for x in targets):
            f.error(where + ("targets",), "targets must be a list of variable paths (structures with X, Y, Z)")
            return None
        checked = []
        for target in targets:
            path = _substitute(target, subst)
            for axis in ("X", "Y", "Z"):
                try:
                    ty = self.type_of(f"{path}.{axis}")
                except (KeyError, ValueError, LookupError) as exc:
                    f.error(where + ("targets",), f"robot view target {path!r} needs a member {axis}: {_reason(exc)}")
                    return None
                if not isinstance(ty, (t.RealType, t.IntType)):
                    f.error(where + ("targets",), f"robot view target {path}.{axis} is {ty.name}, not a number")
                    return None
                self.types[f"{path}.{axis}"] = ty
            checked.append(path)
        out["targets"] = tuple(checked)
        history = table.get("history_s", 20.0)
        if isinstance(history, bool) or not isinstance(history, (int, float)) or not 0 < history <= 3600:
            f.error(where + ("history_s",), f"history_s must be seconds in (0, 3600], got {history!r}")
            return None
        out["history_s"] = float(history)
        ranges = []
        for key in ("x_range", "y_range", "z_range"):
            value = table.get(key, DEFAULT_RANGES[key])
            if not (isinstance(value, (list, tuple)) and len(value) == 2 and
                    all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
                f.error(where + (key,), f"{key} must be [low, high] in mm")
                return None
            if value[0] >= value[1]:
                f.error(where + (key,), f"{key}: low {value[0]} is not below high {value[1]}")
                return None
            ranges.append((float(value[0]), float(value[1])))
        out["ranges"] = tuple(ranges)
        views = table.get("views", ["XY", "XZ"])
        if not isinstance(views, list) or not views or \
                not all(isinstance(v, str) and v.upper() in ("XY", "XZ", "YZ") for v in views):
            f.error(where + ("views",), "views must be a list of projections among \"XY\", \"XZ\", \"YZ\"")
            return None
        out["views"] = tuple(v.upper() for v in views)
        return out

    # ---- presets
    def _read_preset(self, f: _File, where: tuple, table: dict, page: str) -> None:
        self._known(f, where, table, {"name", "label", "values", "step"}, "[[preset]]")
        name = table.get("name")
        if not isinstance(name, str) or not _NAME.match(name):
            f.error(where + ("name",), "preset name must be a name (letters, digits, _)")
            return
        if name in self.presets:
            f.error(where + ("name",), f"preset {name!r} is defined twice (also on page {self.presets[name].page})")
            return
        if ("values" in table) == ("step" in table):
            f.error(where, "a preset has either [preset.values] (one write) or [[preset.step]] tables "
                           "(writes in consecutive scans)")
            return
        raw_steps = [table["values"]] if "values" in table else table["step"]
        step_where = [where + ("values",)] if "values" in table else [where + ("step", i) for i in range(len(raw_steps))]
        steps = []
        for step, at in zip(raw_steps, step_where):
            if not isinstance(step, dict) or not step:
                f.error(at, "preset values are a table of  \"<variable path>\" = value")
                return
            batch = []
            for path, raw in step.items():
                try:
                    ty = self.type_of(path)
                except (KeyError, ValueError, LookupError) as exc:
                    f.error(at + (path,), f"unknown variable path {path!r}: {_reason(exc)}")
                    continue
                if isinstance(ty, (t.StructType, t.ArrayType, t.FBType)):
                    f.error(at + (path,), f"{path} is a {ty.name}: preset its elementary members")
                    continue
                self.types[path] = ty
                if isinstance(raw, dict):
                    run = raw.get("run")
                    if set(raw) != {"run"} or run not in RUN_PARAMETERS:
                        f.error(at + (path,), f"a run value is {{ run = \"NAME\" }} with NAME one of "
                                              f"{', '.join(RUN_PARAMETERS)}")
                        continue
                    batch.append((path, RunParameter(run)))
                    continue
                literal = self._literal(f, at + (path,), path, ty, raw, "")
                if literal is not None:
                    batch.append((path, literal))
                    self._preset_checks.append((f, at + (path,), path, literal))
            steps.append(tuple(batch))
        label = self._string(f, where + ("label",), table.get("label", name))
        self.presets[name] = Preset(name, label, page, tuple(steps))

    # ---- cross-file checks
    def check_references(self) -> None:
        for f, where, kind, name in self._refs:
            if kind == "nav" and name not in self.pages:
                f.error(where, f"no page named {name!r} (pages: {', '.join(self.pages)})")
            elif kind == "preset" and name not in self.presets:
                f.error(where, f"no preset named {name!r} (presets: {', '.join(self.presets) or 'none'})")
            elif kind.startswith("popup:"):
                ids = self._popups.get(kind.split(":", 1)[1], set())
                if name not in ids:
                    f.error(where, f"no popup {name!r} on this page (popups: {', '.join(sorted(ids)) or 'none'})")
        limits = self.limits()
        for f, where, path, literal in self._preset_checks:
            problem = check_limits(limits.get(path), path, literal_number(literal))
            if problem:
                f.error(where, f"preset value {literal} for {path}: {problem}")

    def limits(self) -> dict[str, Limits]:
        out = {}
        for path, users in self._limits.items():
            ty = users[0][0].type
            lo = hi = None
            options = None
            by = []
            for widget, page in users:
                by.append(f"{page}: {widget.label or widget.kind}")
                if widget.min is not None:
                    lo = widget.min if lo is None else max(lo, widget.min)
                if widget.max is not None:
                    hi = widget.max if hi is None else min(hi, widget.max)
                if widget.kind == "dropdown" and isinstance(ty, t.IntType):
                    allowed = {int(v) for _, v in widget.options}
                    options = tuple(sorted(allowed if options is None else set(options) & allowed))
            out[path] = Limits(ty, lo, hi, options, tuple(by))
        return out

    # ---- small readers
    def _literal(self, f: _File, where: tuple, var: str, ty: t.Type, raw: Any, context: str) -> str | None:
        """A TOML value as the IEC literal text written to `var` (checked against its type)."""
        if isinstance(raw, bool):
            text = "TRUE" if raw else "FALSE"
        elif isinstance(raw, (int, float)):
            text = repr(raw)
        elif isinstance(raw, str):
            text = raw
            if isinstance(ty, t.StringType) and not (len(raw) >= 2 and raw[0] == raw[-1] == "'"):
                text = "'" + raw.replace("$", "$$").replace("'", "$'") + "'"
        else:
            f.error(where, f"a value for {var} must be a boolean, number or literal string, got {raw!r}")
            return None
        try:
            value = coerce_python_value(literal_value(text, ty), ty)
        except ValueError as exc:
            f.error(where, f"wrong type: {text} cannot be written to {var} ({ty.name}){context}: {exc}")
            return None
        if isinstance(ty, t.StringType) and len(value) > ty.max_bytes:
            f.error(where, f"{text} is longer than {ty.name} ({ty.max_bytes} bytes)")
            return None
        return text

    def _tables(self, f: _File, where: tuple, raw: Any, what: str) -> list[dict]:
        if not isinstance(raw, list) or not all(isinstance(x, dict) for x in raw):
            f.error(where, f"{what} must be an array of tables ({what})")
            return []
        return raw

    def _known(self, f: _File, where: tuple, table: dict, allowed: set[str], what: str) -> bool:
        ok = True
        for key in table:
            if key not in allowed:
                f.error(where + (key,), f"unknown key {key!r} in {what} (known: {', '.join(sorted(allowed))})")
                ok = False
        return ok

    def _string(self, f: _File, where: tuple, raw: Any) -> str:
        if isinstance(raw, str):
            return raw
        f.error(where, f"must be a string, got {raw!r}")
        return ""


def _paths(widgets) -> tuple[str, ...]:
    seen: dict[str, None] = {}
    for widget in widgets:
        if widget.var:
            seen[widget.var] = None
        for target in widget.targets:
            for axis in ("X", "Y", "Z"):
                seen[f"{target}.{axis}"] = None
    return tuple(seen)


def _substitute(text: str, subst: Mapping[str, str]) -> str:
    """`{n}` in a popup template → the instance (the one placeholder of the format)."""
    if not subst.get("n"):
        return text
    return text.replace("{n}", subst["n"])


def _reason(exc: Exception) -> str:
    text = str(exc.args[0]) if exc.args else str(exc)
    return text.strip("'\"")


def literal_number(literal: str) -> float | None:
    """The number an IEC literal for an integer or REAL stands for (None: not a plain number)."""
    text = literal.strip().replace("_", "")
    sign = -1 if text.startswith("-") else 1
    body = text.lstrip("+-")
    try:
        return sign * float(body) if any(c in body for c in ".eE") and "#" not in body else sign * decode_int(body)
    except (ValueError, KeyError):   # LiteralError is a ValueError; enum names, TRUE, 'text'
        return None


def check_limits(limits: Limits | None, path: str, number: float | None) -> str | None:
    """Why `number` may not be written to `path` under `limits` (None: it may)."""
    if limits is None or number is None:
        return None
    where = f" ({limits.by[0]})" if limits.by else ""
    if limits.min is not None and number < limits.min:
        return f"{_num(number)} is below the minimum {_num(limits.min)}{where}"
    if limits.max is not None and number > limits.max:
        return f"{_num(number)} is above the maximum {_num(limits.max)}{where}"
    if limits.options is not None and int(number) not in limits.options:
        return f"{_num(number)} is not one of the choices {', '.join(map(str, limits.options))}{where}"
    return None


def _num(value: float) -> str:
    return str(int(value)) if float(value).is_integer() else repr(value)
