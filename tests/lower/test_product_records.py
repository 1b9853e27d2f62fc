"""LineMap and LoweredProject (stvm/lower/product.py) are written out by hand for start-up time
and must behave as the dataclasses they were."""

from __future__ import annotations

from stvm.records import FACTORY
from stvm.lower import product
from stvm.semantics import types as t
from stvm.source import Span
from tests.record_helpers import assert_behaves_as_mutable_dataclass, samples_varying

SPAN = Span("a.st", 1, 1, 1, 5)


def test_line_map_behaves_as_its_dataclass():
    first = {"lines": [1, 4], "spans": [SPAN, None]}
    second = {"lines": [2], "spans": [None]}
    assert_behaves_as_mutable_dataclass(product.LineMap, FACTORY,
                                        samples_varying(product.LineMap, first, second))


def test_lowered_project_behaves_as_its_dataclass():
    first = {"source": "x = 1\n", "line_map": product.LineMap([1], [SPAN]), "classes": {"main": "P_Main"},
             "natives": {}, "native_fbs": {}, "types": [t.INT], "sites": [SPAN], "globals_class": "G_globals",
             "layouts": None}
    second = {"source": "", "line_map": product.LineMap(), "classes": {}, "natives": {"N1_ABS": "abs"},
              "native_fbs": {"TON": "ton"}, "types": [], "sites": [], "globals_class": "G_other", "layouts": "x"}
    assert_behaves_as_mutable_dataclass(product.LoweredProject, FACTORY,
                                        samples_varying(product.LoweredProject, first, second))
