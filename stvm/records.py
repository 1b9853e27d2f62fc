"""Value records without `dataclass`'s import cost.

`dataclass` writes each class's `__init__`, `__eq__`, `__hash__` and `__repr__` as source and
`exec`s it when the module is imported: for the ~35 record classes every `stvm run` imports
(types, the semantic model, the project's stages, the settings' tables) that was ~25 ms of a
~190 ms start (issue 33 item 5). A record class here writes its own `__init__` (its
signature is its documentation) and names its fields in `_FIELDS`; `==`, `hash` and `repr` are
derived once from that list, and behave as the dataclass's did: `==` between instances of the
same class over the fields (or `_COMPARED`, a dataclass's `field(compare=False)` left out),
`hash` of the same tuple, `repr` `Name(field=value, …)` safe against cycles, `__match_args__`
for `match`, and pickling through the instance `__dict__`. tests/record_helpers.py compares a
record class with the dataclass made from its fields.
"""

from __future__ import annotations

from dataclasses import FrozenInstanceError
from operator import attrgetter
from reprlib import recursive_repr
from typing import Any, Callable


# The default of a constructor parameter whose dataclass field had a `default_factory`: the
# constructor stores a fresh list or dict when it sees this (`{} if x is FACTORY else x`).
FACTORY: Any = object()


def _key_function(names: tuple[str, ...]) -> Callable[[Any], tuple]:
    """The tuple of `names`' values, in one C call where there are several."""
    if len(names) > 1:
        return attrgetter(*names)
    if names:
        getter = attrgetter(names[0])
        return lambda obj: (getter(obj),)
    return lambda obj: ()


class Record:
    """Mutable and unhashable, as `@dataclass` (eq=True, not frozen)."""

    _FIELDS: tuple[str, ...] = ()            # every field, in order: the constructor's, repr's
    _COMPARED: tuple[str, ...] | None = None   # the fields `==` and `hash` use, when not all

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        cls._key = staticmethod(_key_function(cls._COMPARED if cls._COMPARED is not None else cls._FIELDS))
        cls.__match_args__ = cls._FIELDS

    @recursive_repr()
    def __repr__(self) -> str:
        fields = ", ".join(f"{name}={getattr(self, name)!r}" for name in self._FIELDS)
        return f"{self.__class__.__qualname__}({fields})"

    def __eq__(self, other: object):
        if other.__class__ is self.__class__:
            return self._key(self) == self._key(other)   # type: ignore[attr-defined]
        return NotImplemented

    __hash__ = None   # type: ignore[assignment]  # mutable and compared by value

    def replace(self, **changes):
        """A copy with `changes` (what `dataclasses.replace` gave: the same values otherwise)."""
        unknown = set(changes) - set(self._FIELDS)
        if unknown:
            raise TypeError(f"{self.__class__.__name__} has no field {sorted(unknown)[0]!r}")
        new = self.__class__.__new__(self.__class__)
        new.__dict__.update(self.__dict__)
        new.__dict__.update(changes)
        return new


class FrozenRecord(Record):
    """Frozen and hashable, as `@dataclass(frozen=True)`: the constructor sets its fields with
    `object.__setattr__`; any later assignment raises `FrozenInstanceError`."""

    def __hash__(self) -> int:
        return hash(self._key(self))   # type: ignore[attr-defined]

    def __setattr__(self, name: str, value: object) -> None:
        raise FrozenInstanceError(f"cannot assign to field {name!r}")

    def __delattr__(self, name: str) -> None:
        raise FrozenInstanceError(f"cannot delete field {name!r}")
