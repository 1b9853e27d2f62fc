"""The type classes of stvm/semantics/types.py are written out (start-up time) but must behave as
the `dataclass(frozen=True)` classes they replace: same constructor, `==`, `hash`, `repr`,
frozenness, pickling. Each is compared with a dataclass made from its own `_FIELDS` and defaults."""

from __future__ import annotations

import copy
import dataclasses
import inspect
import pickle

import pytest

from stvm.semantics import types as t

CLASSES = [t.Type, t.BoolType, t.IntType, t.SubrangeType, t.RealType, t.TimeType, t.StringType,
           t.WStringType, t.EnumType, t.StructType, t.UnionType, t.ArrayType, t.FBType,
           t.InterfaceType, t.GenericType, t.RefType, t.VoidType]
NOT_COMPARED = {"fields"}   # StructType/UnionType: a struct type is its name and qualified name


def _reference(cls):
    """The dataclass `cls` was: its fields, in order, with the defaults of its `__init__`."""
    params = inspect.signature(cls.__init__).parameters
    specs = []
    for name in cls._FIELDS:
        default = params[name].default
        kwargs = {} if default is inspect.Parameter.empty else {"default": default}
        if name in NOT_COMPARED:
            kwargs.update(compare=False, hash=False)
        specs.append((name, object, dataclasses.field(**kwargs)))
    return dataclasses.make_dataclass(cls.__qualname__, specs, frozen=True)


def _samples(cls):
    """A few argument tuples, all fields given, differing in each field in turn."""
    base = {"name": "X", "bits": 16, "signed": True, "bitstring": False, "low": 0, "high": 9, "size": 81,
            "qualname": "lib.x", "members": (("A", 0), ("B", 1)), "base": t.INT, "default": 1,
            "strict": True, "to_string": False, "fields": (("a", t.INT),), "element": t.BOOL,
            "dims": ((0, 3),), "rank": 1, "is_program": False, "target": t.DINT, "flavour": "POINTER"}
    other = {"name": "Y", "bits": 32, "signed": False, "bitstring": True, "low": -1, "high": 5, "size": 7,
             "qualname": "lib.y", "members": (("A", 2),), "base": None, "default": None, "strict": False,
             "to_string": True, "fields": (("b", t.REAL),), "element": t.INT, "dims": None, "rank": 2,
             "is_program": True, "target": None, "flavour": "REF_TO"}
    first = tuple(base[f] for f in cls._FIELDS)
    out = [first]
    for i, f in enumerate(cls._FIELDS):
        out.append(first[:i] + (other[f],) + first[i + 1:])
    return out


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_a_type_class_behaves_as_the_frozen_dataclass_it_replaces(cls):
    ref = _reference(cls)
    assert [p for p in inspect.signature(cls.__init__).parameters][1:] == list(cls._FIELDS)
    assert cls.__match_args__ == cls._FIELDS
    samples = _samples(cls)
    for args in samples:
        mine, theirs = cls(*args), ref(*args)
        assert repr(mine) == repr(theirs)
        assert hash(mine) == hash(theirs)
        assert vars(mine) == vars(theirs)   # what pickle stores, in the same order
        assert list(vars(mine)) == list(vars(theirs))
        assert cls(**dict(zip(cls._FIELDS, args))) == mine
        for other in samples:
            assert (mine == cls(*other)) == (theirs == ref(*other))
            assert (mine != cls(*other)) == (theirs != ref(*other))
        back = pickle.loads(pickle.dumps(mine, protocol=pickle.HIGHEST_PROTOCOL))
        assert back == mine and type(back) is cls and vars(back) == vars(mine)
        assert copy.deepcopy(mine) == mine
        with pytest.raises(dataclasses.FrozenInstanceError):
            mine.name = "Z"
        with pytest.raises(dataclasses.FrozenInstanceError):
            del mine.name
    # defaults as the dataclass had them
    assert repr(cls("X")) == repr(ref("X"))


def test_types_of_different_classes_are_never_equal():
    assert t.StringType("STRING", 1986) != t.WStringType("STRING", 1986)
    assert t.StructType("S", "s") != t.UnionType("S", "s")
    assert t.IntType("INT") != t.SubrangeType("INT")
    assert t.StringType("STRING", 1986) == t.STRING and t.STRING.__eq__(1) is NotImplemented


def test_a_struct_type_is_its_names_whatever_its_fields():
    a = t.StructType("S", "s", (("a", t.INT),))
    b = t.StructType("S", "s", (("b", t.REAL),))
    assert a == b and hash(a) == hash(b) and repr(a) != repr(b)
