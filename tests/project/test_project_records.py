"""Project, Parsed, Checked and Compiled (stvm/project.py) are written out by hand for start-up
time and must behave as the dataclasses they were."""

from __future__ import annotations

import pytest

from stvm.records import FACTORY
from stvm import project as p
from stvm.settings import DEFAULT_SETTINGS
from tests.record_helpers import assert_behaves_as_mutable_dataclass, samples_varying

FIRST = {"model": "m", "lowered": "l", "code": (), "sources": {"a.st": "x"}, "settings": DEFAULT_SETTINGS,
         "warnings": [], "from_cache": False, "manifest": {}, "root": None, "native_modules": (),
         "natives_known": False, "files_root": None, "spec": "s", "texts": [("a.st", "x")], "units": [],
         "diagnostics": [], "parsed": "p", "analysis": None, "checker": None, "checked": "c"}
SECOND = {"model": "m2", "lowered": "l2", "code": (1,), "sources": {}, "settings": None, "warnings": ["w"],
          "from_cache": True, "manifest": {"project": {}}, "root": "/r", "native_modules": ("stvm.stdlib.timers",),
          "natives_known": True, "files_root": "/f", "spec": "s2", "texts": [], "units": ["u"],
          "diagnostics": ["d"], "parsed": "p2", "analysis": "a", "checker": "k", "checked": "c2"}


@pytest.mark.parametrize("cls", [p.Project, p.Parsed, p.Checked, p.Compiled], ids=lambda c: c.__name__)
def test_a_stage_product_behaves_as_its_dataclass(cls):
    assert_behaves_as_mutable_dataclass(cls, FACTORY, samples_varying(cls, FIRST, SECOND))
