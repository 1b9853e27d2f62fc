"""One source of limits, units and enumerations for every front end (HMI, OPC UA, `--set`).

A variable's operator limits are declared once and read here:

* a **limits file** (TOML) that the project manifest names, `[hmi] limits = "hmi/limits.toml"`,
  or a `[limits]` table in `stvm.toml` itself; each key is a variable path or a pattern (`*`
  matches any run of characters, `?` one), each value a table::

      [limits]
      "MoveAbs_Param.Speed"          = { min = 0, max = 4500, unit = "% | mm/s", decimals = 0 }
      "*.TargetPosition.X"           = { min = -900, max = 900, unit = "mm", decimals = 2 }
      "*_Busy"                       = { writable = false }

  An exact path wins over a pattern; among patterns the longest (most specific) wins.
* the **HMI page files** (numeric `min`/`max`/`unit`, drop-down options of an integer): a page's
  limits are merged in, the stricter bound wins (`merge_pages`).
* the **ST type**: an enumeration's members are its `enum`; an integer's range bounds `min`/`max`.

Outputs and status are **read-only by default** (`Limits.writable`): a variable is writable only
if it is not CONSTANT, not an output or internal of an FB or PROGRAM instance (`VAR_OUTPUT`,
`VAR`), not named like a status (`DEFAULT_STATUS`: `*_Busy`, `*_Done`, `*.Connected`, …) and no
`writable = false` entry matches it. An entry `writable = true` (exact path or pattern) opens a
variable these rules close; the switch `"@outputs" = { writable = true }` opens them all.

Choice: ST attributes on declarations (`{attribute 'hmi.min' := '0'}`) are not read: stvm's
parser attaches pragmas to POUs and type declarations only, not to single variables.

API (kept small for the OPC UA server: EURange, EngineeringUnits, BadOutOfRange)::

    table = LimitTable.for_project(project, vm)      # or LimitTable(entries, type_of, sections)
    lim = table.limits_for("MoveAbs_Param.Speed")    # Limits(min, max, unit, decimals, enum, writable)
    problem = table.check("MoveAbs_Param.Speed", 9000.0)   # "9000 is above the maximum 4500 …" / None
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping

from stvm.semantics import types as t

MAX_LIMITS_FILE_BYTES = 1 << 20
"""A limits file larger than this is refused (a page file has the same bound)."""

_KEYS = {"min", "max", "unit", "decimals", "enum", "writable", "label"}

OUTPUTS_SWITCH = "@outputs"
"""The key of the switch that opens outputs and status to writes: `"@outputs" = { writable = true }`
(an `@` name cannot clash with an ST path)."""

DEFAULT_STATUS = ("*_Busy", "*_Done", "*_Error", "*_ErrorID", "*_ErrorDescrip", "*_CmdID_Ack",
                  "*.Connected", "*.Socket.*")
"""Status by name, read-only in every project (least specific: any declared entry overrides them).
These are the names the command FBs' outputs are bound to (`Busy => MoveRel_Busy`) and the
connection state a connect FB keeps in its in-out (`Cobot.Connected`, `Cobot.Socket.Handle`)."""


class LimitsError(ValueError):
    """A mistake in a limits table: `where` names the file and key."""

    def __init__(self, where: str, message: str) -> None:
        super().__init__(f"{where}: error: {message}")
        self.where = where
        self.message = message


@dataclass(frozen=True)
class Limits:
    """What an operator may write to one variable, and how its value is shown."""

    min: float | None = None
    max: float | None = None
    unit: str = ""
    decimals: int | None = None            # digits after the point a REAL is shown with
    enum: tuple[str, ...] | None = None    # the allowed names (an enumeration) or literals
    writable: bool = True
    label: str = ""                        # the operator's name for the variable ("Speed")
    by: str = ""                           # where the bound came from, for messages

    def check(self, value: Any) -> str | None:
        """Why `value` may not be written (None: it may), in operator words."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return None
        if isinstance(value, float) and not math.isfinite(value):
            return "not a finite number"
        unit = f" {self.unit}" if self.unit else ""
        if self.min is not None and value < self.min:
            return f"{_num(value)} is below the minimum {_num(self.min)}{unit}"
        if self.max is not None and value > self.max:
            return f"{_num(value)} is above the maximum {_num(self.max)}{unit}"
        return None


def _num(value: float) -> str:
    if float(value).is_integer() and abs(value) < 1e15:
        return str(int(value))
    return f"{value:g}"


def type_limits(ty: t.Type | None) -> Limits:
    """What the ST type alone says (integer range, enumeration members, REAL: 2 decimals)."""
    if isinstance(ty, t.EnumType):
        return Limits(enum=tuple(name for name, _ in ty.members))
    if isinstance(ty, t.IntType) and not isinstance(ty, t.BoolType):
        return Limits(min=ty.lo, max=ty.hi, decimals=0)
    if isinstance(ty, t.RealType):
        return Limits(decimals=2)
    return Limits()


def read_only_by_section(section: str | None, in_instance: bool, constant: bool) -> bool:
    """Outputs and status are read-only: CONSTANT, and an instance's VAR_OUTPUT / VAR members."""
    if constant:
        return True
    return in_instance and section in ("VAR_OUTPUT", "VAR", "VAR_TEMP")


class LimitTable:
    """Declared limits, looked up by variable path (case-insensitive, as ST names are)."""

    def __init__(self, entries: Mapping[str, Mapping[str, Any]] | None = None,
                 type_of: Callable[[str], t.Type] | None = None,
                 section_of: Callable[[str], tuple[str | None, bool, bool]] | None = None,
                 where: str = "[limits]") -> None:
        self.type_of = type_of
        self.section_of = section_of
        self._exact: dict[str, Limits] = {}
        self._patterns: list[tuple[str, re.Pattern, Limits]] = []
        self._cache: dict[str, Limits] = {}
        self.outputs_writable = False   # the `@outputs` switch
        self._defaults = [(_pattern(_norm(p)), p) for p in DEFAULT_STATUS]
        for key, raw in (entries or {}).items():
            self.declare(key, raw, where)

    # ---- building
    def declare(self, key: str, raw: Any, where: str = "[limits]") -> None:
        at = f"{where} {key!r}"
        if not isinstance(key, str) or not key.strip():
            raise LimitsError(at, "a key is a variable path or a pattern such as \"*.Speed\"")
        if not isinstance(raw, Mapping):
            raise LimitsError(at, "the value is a table { min = …, max = …, unit = \"…\" }")
        if key.strip().lower() == OUTPUTS_SWITCH:
            if set(raw) != {"writable"} or not isinstance(raw["writable"], bool):
                raise LimitsError(at, "the switch takes only writable = true or false")
            self.outputs_writable = raw["writable"]
            self._cache.clear()
            return
        unknown = set(raw) - _KEYS
        if unknown:
            raise LimitsError(at, f"unknown key(s) {', '.join(sorted(unknown))} (known: {', '.join(sorted(_KEYS))})")
        fields: dict[str, Any] = {"by": where}
        for bound in ("min", "max"):
            if bound in raw:
                value = raw[bound]
                if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                    raise LimitsError(at, f"{bound} must be a finite number, got {value!r}")
                fields[bound] = value
        if "min" in fields and "max" in fields and fields["min"] > fields["max"]:
            raise LimitsError(at, f"min {fields['min']} is greater than max {fields['max']}")
        for name in ("unit", "label"):
            if name in raw:
                if not isinstance(raw[name], str) or len(raw[name]) > 40:
                    raise LimitsError(at, f"{name} must be a short string")
                fields[name] = raw[name]
        if "decimals" in raw:
            value = raw["decimals"]
            if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 9:
                raise LimitsError(at, f"decimals must be an integer 0..9, got {value!r}")
            fields["decimals"] = value
        if "enum" in raw:
            value = raw["enum"]
            if not isinstance(value, list) or not value or not all(isinstance(x, str) for x in value):
                raise LimitsError(at, "enum must be a non-empty list of names")
            fields["enum"] = tuple(value)
        if "writable" in raw:
            if not isinstance(raw["writable"], bool):
                raise LimitsError(at, "writable must be true or false")
            fields["writable"] = raw["writable"]
        self._cache.clear()
        norm = _norm(key)
        if any(c in norm for c in "*?"):
            self._patterns.append((norm, _pattern(norm), _Partial(fields)))
            self._patterns.sort(key=lambda p: -len(p[0].replace("*", "")))
        else:
            self._exact[norm] = _Partial(fields)

    def merge_pages(self, page_limits: Mapping[str, Any]) -> None:
        """Merge the limits of HMI page files (`stvm.hmi.pages.Limits` per path): the stricter
        bound wins, a unit the table lacks is taken from the page."""
        for path, lim in page_limits.items():
            norm = _norm(path)
            fields = dict(self._exact.get(norm, _Partial({})).fields)
            by = lim.by[0] if getattr(lim, "by", ()) else "HMI page"
            if lim.min is not None and (fields.get("min") is None or lim.min > fields["min"]):
                fields["min"] = lim.min
                fields["by"] = by
            if lim.max is not None and (fields.get("max") is None or lim.max < fields["max"]):
                fields["max"] = lim.max
                fields["by"] = by
            if getattr(lim, "unit", "") and not fields.get("unit"):
                fields["unit"] = lim.unit
            if getattr(lim, "options", None) and "enum" not in fields:
                fields["enum"] = tuple(str(v) for v in lim.options)
            self._exact[norm] = _Partial(fields)
        self._cache.clear()

    @classmethod
    def for_project(cls, project: Any, vm: Any = None) -> "LimitTable":
        """The table of a project: its manifest's `[limits]` and the file `[hmi] limits` names;
        with `vm`, types and sections come from the running program."""
        manifest = getattr(project, "manifest", None) or {}
        root = Path(getattr(project, "root", None) or ".")
        type_of = section_of = None
        if vm is not None:
            type_of = lambda path: vm.accessor(path).type   # noqa: E731
            section_of = _sections(vm)
        table = cls(None, type_of, section_of)
        inline = manifest.get("limits")
        if inline is not None:
            if not isinstance(inline, Mapping):
                raise LimitsError("stvm.toml [limits]", "must be a table of \"<path>\" = { … }")
            for key, raw in inline.items():
                table.declare(key, raw, "stvm.toml [limits]")
        hmi = manifest.get("hmi")
        name = hmi.get("limits") if isinstance(hmi, Mapping) else None
        if name is not None:
            if not isinstance(name, str):
                raise LimitsError("stvm.toml [hmi] limits", "must be a file name")
            for key, raw in read_limits_file(root / name).items():
                table.declare(key, raw, name)
        return table

    # ---- lookups
    def limits_for(self, path: str) -> Limits:
        """The limits of `path`: declared ones over the type's own; `writable` by the rule above."""
        norm = _norm(path)
        found = self._cache.get(norm)
        if found is not None:
            return found
        ty = None
        if self.type_of is not None:
            try:
                ty = self.type_of(path)
            except Exception:   # noqa: BLE001 - an unknown path has only what is declared
                ty = None
        fields = dict(type_limits(ty).__dict__)
        writable = True
        if not self.outputs_writable:
            if self.section_of is not None:
                section = self.section_of(norm)
                if section is not None and read_only_by_section(*section):
                    writable = False
            if any(regex.match(norm) for regex, _ in self._defaults):
                writable = False
        fields["writable"] = writable
        # patterns first (least specific first), the exact entry last: it wins
        for pattern, regex, partial in reversed(self._patterns):
            if regex.match(norm):
                fields.update(partial.fields)
        exact = self._exact.get(norm)
        if exact is not None:
            fields.update(exact.fields)
        # a declared range never widens what the type can hold
        type_range = type_limits(ty)
        if type_range.min is not None:
            fields["min"] = max(fields["min"], type_range.min) if fields.get("min") is not None else type_range.min
            fields["max"] = min(fields["max"], type_range.max) if fields.get("max") is not None else type_range.max
        found = Limits(**fields)
        self._cache[norm] = found
        return found

    def check(self, path: str, value: Any) -> str | None:
        """Why `value` may not be written to `path` (None: it may)."""
        lim = self.limits_for(path)
        if not lim.writable:
            return "read-only (an output or status)"
        return lim.check(value)


@dataclass(frozen=True)
class _Partial:
    fields: dict


def _pattern(norm: str) -> re.Pattern:
    # `[` is an array index here, not a character class: only * and ? are wildcards
    regex = "".join(".*" if c == "*" else "." if c == "?" else re.escape(c) for c in norm)
    return re.compile(regex + r"\Z")


def _norm(path: str) -> str:
    return path.replace(" ", "").lower()


def read_limits_file(path: Path) -> dict[str, Any]:
    """A limits file's `[limits]` table (the whole file may also be the bare table)."""
    try:
        with open(path, "rb") as fh:
            data = fh.read(MAX_LIMITS_FILE_BYTES + 1)
    except OSError as exc:
        raise LimitsError(str(path), f"cannot read the limits file: {exc.strerror or exc}") from None
    if len(data) > MAX_LIMITS_FILE_BYTES:
        raise LimitsError(str(path), f"limits file larger than {MAX_LIMITS_FILE_BYTES} bytes")
    try:
        parsed = tomllib.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise LimitsError(str(path), f"not a TOML file: {exc}") from None
    table = parsed.get("limits", parsed)
    if not isinstance(table, dict):
        raise LimitsError(str(path), "[limits] must be a table")
    return table


def _sections(vm: Any) -> Callable[[str], tuple[str | None, bool, bool] | None]:
    """path → (declaring section, inside an instance, constant), from the catalog."""
    info: dict[str, tuple[str | None, bool, bool]] | None = None

    def section_of(norm: str):
        nonlocal info
        if info is None:
            from stvm.runtime.catalog import catalog   # lazy: start-up
            info = {}
            for root in catalog(vm):
                for node in root.walk():
                    if node.leaf:
                        # a program's own VAR_OUTPUT / VAR are its instance's members too
                        inside = node.in_fb or (root.kind == "program" and node is not root)
                        info[_norm(node.path)] = (node.section, inside, node.constant)
        return info.get(norm)
    return section_of
