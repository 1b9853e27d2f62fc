"""Differential test of the lowering's optimisations (stvm/lower/options.py, issue 18 item 4).

Every optimisation only changes how fast the generated code runs, never what it computes. The
core statement, POU and type suites (tests/runtime: a few hundred small PROGRAMs, each with its
expected values) and the thesis PnP golden trace are run with every optimisation off
(`LowerOptions.none()`) and with each single one off, and compared with the default build:
the same values, the same faults, the same trace bytes. The per-optimisation tests of the
scan-time switches are in test_lower_scan_options.py.
"""

from __future__ import annotations

import importlib.util
import sys
from functools import lru_cache
from pathlib import Path

import pytest

from core_helpers import run_cases
from stvm.lower.options import DEFAULT_OPTIONS, LowerOptions
from test_lower_scan_options import lowering

TESTS = Path(__file__).resolve().parents[1]
CORE_SUITES = {   # module under tests/runtime → its list of StCase
    "test_runtime_statements": "CASES",
    "test_runtime_pous": "POU_CASES",
    "test_runtime_types": "TYPE_CASES",
}
# the reference build, then each optimisation alone switched off
VARIANTS = {"none": LowerOptions.none()} | {f"no_{name}": DEFAULT_OPTIONS.without(name)
                                            for name in LowerOptions.names()}


@lru_cache(maxsize=None)
def core_cases(module: str):
    spec = importlib.util.spec_from_file_location(f"_differential_{module}", TESTS / "runtime" / f"{module}.py")
    loaded = importlib.util.module_from_spec(spec)   # type: ignore[arg-type]
    spec.loader.exec_module(loaded)                  # type: ignore[union-attr]
    return tuple(getattr(loaded, CORE_SUITES[module]))


def outcomes(module: str, options: LowerOptions) -> dict[str, tuple]:
    with lowering(options):
        results = run_cases(core_cases(module))
    return {name: (sorted(map(repr, r.values.items())), r.error) for name, r in results.items()}


@lru_cache(maxsize=None)
def default_outcomes(module: str) -> dict[str, tuple]:
    return outcomes(module, DEFAULT_OPTIONS)


def test_every_optimisation_is_a_variant():
    assert set(VARIANTS) == {"none"} | {f"no_{name}" for name in LowerOptions.names()}
    assert all(not getattr(VARIANTS["none"], name) for name in LowerOptions.names())


@pytest.mark.parametrize("module", sorted(CORE_SUITES))
@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_core_suite_computes_the_same(variant, module):
    expected = default_outcomes(module)
    got = outcomes(module, VARIANTS[variant])
    assert len(got) == len(expected) > 10
    differing = {name: (got[name], expected[name]) for name in expected if got.get(name) != expected[name]}
    assert not differing, f"{variant} changes {len(differing)} case(s): {differing}"


def thesis_trace(options: LowerOptions, name: str = "pnp_cycle") -> tuple[str, str]:
    """(generated code, JSONL trace) of a thesis golden scenario lowered with `options`."""
    sys.path.insert(0, str(TESTS / "trace"))
    from trace_helpers import SCENARIOS, THESIS
    from stvm.project import load
    from stvm.trace import TraceSpec, run_trace
    from stvm.trace.writers import to_jsonl
    with lowering(options):
        project = load([THESIS / "PnP_Example.st"], use_cache=False)
    run = run_trace(TraceSpec([THESIS / "PnP_Example.st"], scenario=SCENARIOS / f"golden_{name}.toml"), project)
    return project.lowered.source, to_jsonl(run.trace)


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_thesis_pnp_golden_is_the_same(variant):
    """The PnP cycle trace is byte-identical to the golden (which the default build produces, see
    tests/trace/test_thesis_goldens.py) with the optimisations off. Compared, never written."""
    code, trace = thesis_trace(VARIANTS[variant])
    assert trace == (TESTS / "golden" / "pnp_cycle.jsonl").read_text(encoding="utf-8")
    if variant == "none":   # really the unoptimised build
        assert "for v_" not in code and "_impl.call(v_" not in code and "_ar := " not in code
