"""Helpers for calling native stdlib POUs directly, scan by scan, without the core.

(Not a conftest.py: test modules import these names, and several conftest modules would clash.)
"""

from __future__ import annotations

import sys
from pathlib import Path
from types import SimpleNamespace

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import stvm.stdlib  # noqa: E402
stvm.stdlib.load_natives()   # fills the registry
from stvm.runtime.context import RunContext  # noqa: E402
from stvm.settings import SysmacSettings  # noqa: E402
from stvm.stdlib.registry import NATIVE_FBS, NATIVE_FUNCTIONS  # noqa: E402

MS = 1_000_000
S = 1_000_000_000


def make_ctx(**settings) -> RunContext:
    """A RunContext at virtual time 0, scan 0, with the given setting overrides."""
    ctx = RunContext(settings=SysmacSettings(**settings))
    ctx.warnings = []
    ctx.warn_sink = ctx.warnings.append
    return ctx


def call(name: str, ctx: RunContext, *args, result_type=None, arg_types=None):
    """Call a native function the way the VM does (registry conventions)."""
    native = NATIVE_FUNCTIONS[name.upper()]
    prefix = []
    if native.generic:
        prefix.append(result_type)
    if native.typed:
        prefix.append(arg_types)
    return native.impl(ctx, *prefix, *args)


class FBRunner:
    """One native FB instance: `inst` holds the v_* variables, `step()` is one call."""

    def __init__(self, name: str, ctx: RunContext, **variables) -> None:
        self.impl = NATIVE_FBS[name.upper()]()
        self.ctx = ctx
        self.inst = SimpleNamespace(**{f"v_{key.lower()}": value for key, value in variables.items()})

    def step(self, **inputs):
        for key, value in inputs.items():
            setattr(self.inst, f"v_{key.lower()}", value)
        self.impl.call(self.inst, self.ctx)
        return self.inst

    def __getattr__(self, name):
        return getattr(self.inst, f"v_{name.lower()}")

