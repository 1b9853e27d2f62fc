"""Static limits on what a declaration may ask for (issue 34 item 9), each a small function the
checker calls, with an error in ST terms.

* Array bounds are DINT, as in IEC 61131-3 and CODESYS/Sysmac (a bound beyond it is refused,
  not carried as a 64-bit or bigger Python int into the layout).
* One array variable holds at most `max_array_elements` elements, nested arrays multiplied (the
  setting; 16,777,216 by default): the VM keeps one Python object per element, so
  `ARRAY[0..2000000000] OF INT` would exhaust memory at start-up instead of failing the check.
"""

from __future__ import annotations

from stvm.semantics import types as t

DINT_MIN, DINT_MAX = -2**31, 2**31 - 1


def array_bounds_problem(lo: int, hi: int) -> str | None:
    """Why `lo..hi` cannot be an array dimension (None if it can)."""
    for bound in (lo, hi):
        if not DINT_MIN <= bound <= DINT_MAX:
            shown = str(bound) if len(str(bound)) <= 24 else f"{str(bound)[:20]}… ({len(str(bound))} digits)"
            return f"array bound {shown} is outside DINT ({DINT_MIN}..{DINT_MAX})"
    return None


def element_count(dims: list[tuple[int, int]] | tuple[tuple[int, int], ...], element: t.Type) -> int:
    """How many scalar elements an array of `dims` over `element` holds (nested arrays multiplied)."""
    total = 1
    for lo, hi in dims:
        total *= hi - lo + 1
    while isinstance(element, t.ArrayType) and element.dims:
        total *= element.length
        element = element.element
    return total


def array_size_problem(dims, element: t.Type, limit: int) -> str | None:
    """Why an array of `dims` over `element` is too large (None if it is not)."""
    count = element_count(dims, element)
    if count > limit:
        return (f"this array has {count:,} elements, more than the limit of {limit:,} "
                f"(setting max_array_elements)")
    return None
