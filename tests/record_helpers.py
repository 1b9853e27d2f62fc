"""Checks that a class written out by hand (start-up time, issue 33 item 5) behaves as the
mutable `@dataclass` it replaces: compared with a dataclass made from its `_FIELDS` and the
defaults of its `__init__` (`factory`: the sentinel standing for a `default_factory`)."""

from __future__ import annotations

import copy
import dataclasses
import inspect
import pickle


def reference(cls, factory: object, frozen: bool = False):
    params = inspect.signature(cls.__init__).parameters
    specs = []
    for name in cls._FIELDS:
        default = params[name].default
        if default is factory:
            specs.append((name, object, dataclasses.field(default_factory=_FactoryOf(cls, name))))
        elif default is inspect.Parameter.empty:
            specs.append((name, object))
        else:
            specs.append((name, object, dataclasses.field(default=default)))
    return dataclasses.make_dataclass(cls.__qualname__, specs, frozen=frozen)


class _FactoryOf:
    """What the hand-written class puts in a field given no argument (a fresh empty list/dict)."""

    def __init__(self, cls, name: str) -> None:
        self.cls, self.name = cls, name

    def __call__(self):
        required = [p for p in list(inspect.signature(self.cls.__init__).parameters.values())[1:]
                    if p.default is inspect.Parameter.empty]
        return type(getattr(self.cls(*(None for _ in required)), self.name))()


def assert_behaves_as_mutable_dataclass(cls, factory: object, samples: list[tuple]) -> None:
    ref = reference(cls, factory)
    assert cls.__match_args__ == cls._FIELDS == tuple(inspect.signature(cls.__init__).parameters)[1:]
    for args in samples:
        mine, theirs = cls(*args), ref(*args)
        assert repr(mine) == repr(theirs)
        assert list(vars(mine).items()) == list(vars(theirs).items())
        for other in samples:
            assert (mine == cls(*other)) == (theirs == ref(*other))
        assert (mine == object()) is False
        try:
            back = pickle.loads(pickle.dumps(mine, protocol=pickle.HIGHEST_PROTOCOL))
        except (pickle.PicklingError, TypeError, AttributeError):
            back = copy.copy(mine)   # a sample holding something unpicklable: compare a copy
        assert back == mine and type(back) is cls
        try:
            hash(mine)
        except TypeError:
            pass
        else:
            raise AssertionError(f"{cls.__name__} is mutable and compared by value: unhashable")
    # the defaults: as many fresh objects as instances
    required = [p for p in list(inspect.signature(cls.__init__).parameters.values())[1:]
                if p.default is inspect.Parameter.empty]
    a, b = cls(*(None for _ in required)), cls(*(None for _ in required))
    assert repr(a) == repr(ref(*(None for _ in required))) and a == b
    for name in cls._FIELDS:
        if inspect.signature(cls.__init__).parameters[name].default is factory:
            assert getattr(a, name) is not getattr(b, name)


def samples_varying(cls, first: dict, second: dict) -> list[tuple]:
    """All fields from `first`, then each field in turn from `second`."""
    base = tuple(first[f] for f in cls._FIELDS)
    return [base] + [base[:i] + (second[f],) + base[i + 1:] for i, f in enumerate(cls._FIELDS)]
