"""The classes of stvm/semantics/model.py are written out (start-up time) but must behave as the
dataclasses they replace: constructor and defaults (a fresh dict where the dataclass had a
`default_factory`), `==` over every field, `repr`, frozenness (the two frozen ones) or
unhashability (the mutable ones), pickling. Each is compared with a dataclass made from its
own `_FIELDS` and `__init__` defaults."""

from __future__ import annotations

import copy
import dataclasses
import inspect
import pickle

import pytest

from stvm.records import FACTORY
from stvm.semantics import model as m
from stvm.semantics import types as t
from stvm.source import Span

FROZEN = [m.SiblingInstance, m.AddressInit]
MUTABLE = [m.Variable, m.POUInfo, m.PropertyInfo, m.TaskInfo, m.ProjectModel]
SPAN = Span("a.st", 3, 1, 3, 9)


def _reference(cls, frozen: bool):
    params = inspect.signature(cls.__init__).parameters
    specs = []
    for name in cls._FIELDS:
        default = params[name].default
        if default is FACTORY:
            specs.append((name, object, dataclasses.field(default_factory=dict)))
        elif default is inspect.Parameter.empty:
            specs.append((name, object))
        else:
            specs.append((name, object, dataclasses.field(default=default)))
    return dataclasses.make_dataclass(cls.__qualname__, specs, frozen=frozen)


def _value(name: str, variant: int):
    values = {"name": ("x", "y"), "qualname": ("ns\\x", "ns\\y"), "kind": ("FUNCTION", "METHOD"),
              "section": ("VAR", "VAR_INPUT"), "type": (t.INT, t.REAL), "return_type": (None, t.BOOL),
              "span": (SPAN, Span("b.st", 1, 1, 1, 2)), "init": (None, 5), "fb_args": (None, {"a": 1}),
              "scope": ("self", "global"), "steps": ((("field", "a"),), (("item", 2),)),
              "programs": ([("p", "Main")], []), "interval_ns": (1, 2), "priority": (0, 1),
              "getter": (None, "getter"), "setter": (None, "setter"), "access": ("PUBLIC", "PRIVATE"),
              "file": ("", "a.st"), "quiet_pin": (None, "execute"), "base": (None, "fb_base"),
              "interfaces": ((), ("i_x",)), "owner": ("", "fb"), "inherited": (0, 2),
              "default_programs": (["main"], [])}
    if name in values:
        return values[name][variant]
    return [{}, {"k": "v"}][variant] if name in ("variables", "aliases", "methods", "properties", "inst_vars",
                                                 "stat_vars", "pous", "globals", "structs", "enums") else \
        [[], ["t"]][variant] if name == "tasks" else bool(variant)


def _samples(cls):
    first = tuple(_value(f, 0) for f in cls._FIELDS)
    return [first] + [first[:i] + (_value(f, 1),) + first[i + 1:] for i, f in enumerate(cls._FIELDS)]


@pytest.mark.parametrize("cls", FROZEN + MUTABLE, ids=lambda c: c.__name__)
def test_a_model_class_behaves_as_the_dataclass_it_replaces(cls):
    frozen = cls in FROZEN
    ref = _reference(cls, frozen)
    assert cls.__match_args__ == cls._FIELDS == tuple(inspect.signature(cls.__init__).parameters)[1:]
    samples = _samples(cls)
    for args in samples:
        mine, theirs = cls(*args), ref(*args)
        assert repr(mine) == repr(theirs)
        assert list(vars(mine).items()) == list(vars(theirs).items())
        for other in samples:
            assert (mine == cls(*other)) == (theirs == ref(*other))
        back = pickle.loads(pickle.dumps(mine, protocol=pickle.HIGHEST_PROTOCOL))
        assert back == mine and type(back) is cls
        assert copy.deepcopy(mine) == mine
        if frozen:
            assert hash(mine) == hash(theirs)
            with pytest.raises(dataclasses.FrozenInstanceError):
                mine.name = "z"
        else:
            with pytest.raises(TypeError):
                hash(mine)
            setattr(mine, cls._FIELDS[0], "changed")
            assert mine != cls(*args)
    assert (cls(*samples[0]) == object()) is False


def test_defaults_are_fresh_where_the_dataclass_had_a_factory():
    a, b = m.POUInfo("f", "f", "FUNCTION", None), m.POUInfo("f", "f", "FUNCTION", None)
    assert a == b and a.variables is not b.variables and a.methods == {} and a.inst_vars is not b.inst_vars
    assert repr(a) == repr(_reference(m.POUInfo, False)("f", "f", "FUNCTION", None))


def test_pou_replace_is_what_dataclasses_replace_gave():
    pou = m.POUInfo("M", "fb.M", "METHOD", t.INT, {"a": m.Variable("a", "VAR_INPUT", t.INT)}, owner="fb")
    ref = _reference(m.POUInfo, False)
    theirs = dataclasses.replace(ref(*(getattr(pou, f) for f in m.POUInfo._FIELDS)), access="PRIVATE", kind="FUNCTION")
    mine = pou.replace(access="PRIVATE", kind="FUNCTION")
    assert repr(mine) == repr(theirs) and mine.variables is pou.variables and pou.access == "PUBLIC"
    with pytest.raises(TypeError):
        pou.replace(nonsense=1)
