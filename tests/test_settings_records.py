"""stvm/settings.py writes out, for start-up time, what `dataclass` generated with `exec`: Table and
Declaration entirely, SysmacSettings's ==, hash and repr (its repr is part of the compile cache
key). They must behave as the dataclass code did."""

from __future__ import annotations

import dataclasses
import inspect
import pickle

import pytest

from stvm import settings as s


def _reference(cls):
    specs = [(name, object) for name in cls._FIELDS]
    return dataclasses.make_dataclass(cls.__qualname__, specs, frozen=True)


@pytest.mark.parametrize("cls,first,second", [
    (s.Table, (("a", "b"), 0, 9, True), (("c",), -1, 5, False)),
    (s.Declaration, ("x", int, 1, "5", 0, 9, None, "doc"), ("y", dict, {"a": 1}, "6", None, None, s.Table(("a",), 0, 1, False), "")),
], ids=["Table", "Declaration"])
def test_table_and_declaration_behave_as_their_frozen_dataclasses(cls, first, second):
    ref = _reference(cls)
    assert cls.__match_args__ == cls._FIELDS == tuple(inspect.signature(cls.__init__).parameters)[1:]
    samples = [first] + [first[:i] + (second[i],) + first[i + 1:] for i in range(len(first))]
    for args in samples:
        mine, theirs = cls(*args), ref(*args)
        assert repr(mine) == repr(theirs) and list(vars(mine).items()) == list(vars(theirs).items())
        for other in samples:
            assert (mine == cls(*other)) == (theirs == ref(*other))
        try:
            assert hash(mine) == hash(theirs)
        except TypeError:   # a dict inside: unhashable in both
            with pytest.raises(TypeError):
                hash(theirs)
        assert pickle.loads(pickle.dumps(mine)) == mine
        with pytest.raises(dataclasses.FrozenInstanceError):
            mine.name = "z"


def _dataclass_repr(settings) -> str:
    shown = ", ".join(f"{f.name}={getattr(settings, f.name)!r}" for f in dataclasses.fields(settings) if f.repr)
    return f"SysmacSettings({shown})"


def _compared(settings) -> tuple:
    return tuple(getattr(settings, f.name) for f in dataclasses.fields(settings) if f.compare)


def test_sysmac_settings_repr_and_equality_are_the_dataclass_ones():
    default = s.DEFAULT_SETTINGS
    variants = [default, default.with_overrides(["int_literal_type=lint"]),
                default.with_overrides(["dialect=twincat"]), default.with_defines(["A=1"]),
                dataclasses.replace(default, rtfs_max_minlen=5)]
    for a in variants:
        assert repr(a) == _dataclass_repr(a)
        assert "_explicit" not in repr(a) and "_profile_dialect" not in repr(a)
        for b in variants:
            assert (a == b) == (_compared(a) == _compared(b))
        assert a == pickle.loads(pickle.dumps(a))
    # `_explicit` is left out of ==, as the dataclass field said (compare=False)
    assert dataclasses.replace(default, _explicit=frozenset({"x"})) == default
    with pytest.raises(TypeError):   # table settings hold dicts: unhashable, as before
        hash(default)
    assert default.__eq__(object()) is NotImplemented
    with pytest.raises(dataclasses.FrozenInstanceError):
        default.array_oob = s.ArrayOob.FAULT
