"""EURange and EngineeringUnits of a variable the operator limits table bounds (OPC UA Part 8).

A variable whose limits (stvm/frontend/limits.py) declare a range narrower than its ST type's, or
a range on a REAL, is published as an AnalogItemType with an `EURange` property (Range: Low,
High); one with a `unit` has an `EngineeringUnits` property (EUInformation). The integer range an
ST type alone gives (UINT's 0..65535) is not an engineering range and gets no property.

EngineeringUnits follow Part 8 §5.6.3: the UNECE Recommendation 20 common code of the unit, its
UnitId (the code's ASCII characters packed into an Int32, first character highest) and the
namespace `http://www.opcfoundation.org/UA/units/un/cefact`. A unit without a UNECE code
(the thesis's `% | mm/s`: percent for PTP, mm/s for a line) is published with UnitId -1 and its
text as DisplayName (Part 8: -1 means "no UnitId").
"""

from __future__ import annotations

from asyncua import ua

from stvm.frontend.limits import Limits, type_limits
from stvm.semantics import types as t

UNECE_NAMESPACE = "http://www.opcfoundation.org/UA/units/un/cefact"

# the units the thesis project and typical cells use → UNECE Rec. 20 common code
UNECE_CODES = {
    "mm": "MMT", "m": "MTR", "cm": "CMT", "°": "DD", "deg": "DD", "rad": "C81",
    "ms": "C26", "s": "SEC", "min": "MIN", "h": "HUR", "%": "P1",
    "mm/s": "C16", "m/s": "MTS", "°/s": "E96", "kg": "KGM", "g": "GRM", "n": "NEW", "nm": "NU",
    "v": "VLT", "a": "AMP", "w": "WTT", "°c": "CEL", "hz": "HTZ", "bar": "BAR", "rpm": "RPM",
}


def unit_id(code: str) -> int:
    """Part 8 §5.6.3: the common code's characters packed into an Int32, the first one highest."""
    value = 0
    for char in code:
        value = value << 8 | ord(char)
    return value


def eu_information(unit: str) -> ua.EUInformation:
    code = UNECE_CODES.get(unit.strip().lower())
    return ua.EUInformation(NamespaceUri=UNECE_NAMESPACE, UnitId=unit_id(code) if code else -1,
                            DisplayName=ua.LocalizedText(unit), Description=ua.LocalizedText(unit))


def eu_range(limits: Limits, ty: t.Type) -> ua.Range | None:
    """The EURange of a variable, or None when its limits are only its type's."""
    if limits.min is None or limits.max is None:
        return None
    own = type_limits(ty)
    if (own.min, own.max) == (limits.min, limits.max):
        return None
    return ua.Range(Low=float(limits.min), High=float(limits.max))
