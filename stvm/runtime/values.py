"""Runtime value helpers shared by generated code and native POUs.

Native stdlib code receives plain Python values (see `stvm.semantics.types` for the table) plus
these few wrappers:

* `ArrayRef(data, start, lo)`: an ARRAY[*] parameter. Sysmac passes "the array from this element on"
  when an element is given where an array is expected (sysmac.md 3 #4); `data` is the caller's own
  list, so writes go straight into the caller's variable. `len(ref)` is the number of elements left.
* `AttrRef` / `ItemRef`: a VAR_IN_OUT of an elementary type (a reference to a variable, a struct
  field or an array element) with `get()` and `set(value)`.
* `FunctionError`: raised by a native function to report an instruction error (ENO := FALSE); the
  VM then applies `SysmacSettings.fun_error_policy` (default: skip the receiving assignment).
* `STFault`: a major fault (division by zero, index out of range); stops the task.
* `ArrayIndexError`: an array index out of range in user code; a fault unless
  `SysmacSettings.array_oob` is `skip_statement` (then the generated code skips the statement).
"""

from __future__ import annotations


class FunctionError(Exception):
    """An instruction error: the function sets ENO FALSE and leaves its output unchanged."""


class STFault(Exception):
    """A major fault: the task stops; the VM adds the ST location, task and scan."""


class ArrayIndexError(STFault):
    """An array index out of range in user code (sysmac.md 1, `array_oob`)."""


class ArrayRef:
    # `lo`: the ST index of the first element passed — 0, except under `open_array_bounds=actual`
    # where a whole ARRAY[lo..hi] keeps its bounds (LOWER_BOUND/UPPER_BOUND read them here)
    __slots__ = ("data", "start", "lo")

    def __init__(self, data: list, start: int = 0, lo: int = 0) -> None:
        self.data = data
        self.start = start
        self.lo = lo

    def __len__(self) -> int:
        return len(self.data) - self.start

    def __getitem__(self, index: int):
        if not 0 <= index < len(self.data) - self.start:
            raise FunctionError(f"array access {index} beyond the {len(self)} elements passed")
        return self.data[self.start + index]

    def __setitem__(self, index: int, value) -> None:
        if not 0 <= index < len(self.data) - self.start:
            raise FunctionError(f"array access {index} beyond the {len(self)} elements passed")
        self.data[self.start + index] = value

    def read(self, count: int) -> list:
        """The first `count` elements (the caller checked `count <= len(self)`)."""
        return self.data[self.start:self.start + count]

    def write(self, values) -> None:
        """Overwrite the first len(values) elements; later elements are not touched."""
        values = list(values)
        if len(values) > len(self):
            raise FunctionError(f"{len(values)} elements do not fit in the {len(self)} passed")
        self.data[self.start:self.start + len(values)] = values


class OpenArray:
    """An array passed to an ARRAY[*, *] parameter (IEC ed. 3 6.5.3.2): the nested lists of the
    argument (never copied) and, per dimension, the (lo, hi) the callee indexes with — from 0, or
    the argument's own bounds under `open_array_bounds=actual`."""

    __slots__ = ("data", "bounds")

    def __init__(self, data: list, bounds: tuple[tuple[int, int], ...]) -> None:
        self.data = data
        self.bounds = bounds


class AttrRef:
    """Reference to `obj.<attr>` (a variable of a POU instance or a struct field)."""

    __slots__ = ("obj", "attr")

    def __init__(self, obj, attr: str) -> None:
        self.obj = obj
        self.attr = attr

    def get(self):
        return getattr(self.obj, self.attr)

    def set(self, value) -> None:
        setattr(self.obj, self.attr, value)

    def same(self, other) -> bool:
        """The same variable (REF_TO comparison `r1 = r2`)."""
        return type(other) is AttrRef and other.obj is self.obj and other.attr == self.attr


class ItemRef:
    """Reference to `lst[index]` (an array element)."""

    __slots__ = ("lst", "index")

    def __init__(self, lst: list, index: int) -> None:
        self.lst = lst
        self.index = index

    def get(self):
        return self.lst[self.index]

    def set(self, value) -> None:
        self.lst[self.index] = value

    def same(self, other) -> bool:
        return type(other) is ItemRef and other.lst is self.lst and other.index == self.index


class MapRef:
    """A reference that converts what is stored through it (a function output bound with `=>`
    to a variable of a wider type)."""

    __slots__ = ("ref", "convert")

    def __init__(self, ref, convert) -> None:
        self.ref = ref
        self.convert = convert

    def get(self):
        return self.ref.get()

    def set(self, value) -> None:
        self.ref.set(self.convert(value))
