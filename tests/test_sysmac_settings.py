"""`stvm/settings.py`: every Sysmac setting is declared once (type, default, spec section), every
value from Python, `--sysmac`, or `stvm.toml` is checked against it, and the meta-tests below hold
the code to the declarations:

* every setting is read somewhere outside its declaration, and no read compares it with a
  free string or number (reads compare with the declared Enum members);
* every alternative value of every setting changes something a test observes: `OBSERVED` maps
  each (setting, alternative) to a probe below (run under the default and the alternative: the
  results must differ) or to the test that asserts the alternative's behaviour (it must exist
  and name the setting and the value);
* the settings table of docs/sysmac_behaviours.md is the declarations' table.
"""

from __future__ import annotations

import ast
import re
from enum import Enum
from pathlib import Path
from typing import Any, Callable

import pytest

import stvm
from core_helpers import load_st, write_st
from dataclasses import replace

from stvm.dialects import PROFILE_FIELDS
from stvm.settings import (
    DEFAULT_SETTINGS, Declaration, Dialect, SettingError, SysmacSettings, declarations,
)

ROOT = Path(__file__).resolve().parents[1]
DECLARED = {d.name: d for d in declarations()}


# ---- declarations ----------------------------------------------------------------------------

@pytest.mark.parametrize("name", list(DECLARED))
def test_every_setting_declares_its_values_default_and_spec(name):
    d = DECLARED[name]
    assert d.spec and d.meaning, name
    if d.choices:
        assert isinstance(d.default, d.kind) and len(d.choices) >= 1
        assert getattr(DEFAULT_SETTINGS, name) is d.default
    elif d.table is not None:
        assert d.table.check(name, d.default) == d.default
    else:
        assert d.kind is int and d.lo is not None and d.hi is not None and d.lo <= d.default <= d.hi


@pytest.mark.parametrize("name", [d.name for d in declarations() if d.choices])
def test_an_unknown_value_lists_the_allowed_ones(name):
    d = DECLARED[name]
    # None is "the dialect's value" for a setting a dialect profile decides
    for bad in ("nonsense", True, 2.5) + (() if name in PROFILE_FIELDS else (None,)):
        with pytest.raises(SettingError) as info:
            SysmacSettings(**{name: bad})
        message = str(info.value)
        assert message.startswith(f"{name}: {bad!r} is not allowed; allowed: ")
        assert all(str(member.value) in message for member in d.choices)
        assert f"{d.default.value} (default)" in message
    for member in d.choices:   # the spelling (any case) and the member itself are accepted
        assert getattr(SysmacSettings(**{name: member}), name) is member
        spelling = str(member.value).upper()
        assert getattr(DEFAULT_SETTINGS.with_overrides([f"{name}={spelling}"]), name) is member


@pytest.mark.parametrize("name", [d.name for d in declarations() if d.kind is int])
def test_numbers_outside_their_range_are_rejected_with_the_range(name):
    d = DECLARED[name]
    for bad in (d.lo - 1, d.hi + 1):
        with pytest.raises(SettingError, match=rf"{name}: {bad} is out of range; allowed: an integer "
                                               rf"{d.lo}\.\.{d.hi} \(default {d.default}\)"):
            SysmacSettings(**{name: bad})
    for bad in ("12", 1.0, False):
        with pytest.raises(SettingError, match="is not allowed"):
            SysmacSettings(**{name: bad})
    with pytest.raises(SettingError, match="is not an integer"):
        DEFAULT_SETTINGS.with_overrides([f"{name}=twelve"])
    assert getattr(DEFAULT_SETTINGS.with_overrides([f"{name}={d.lo}"]), name) == d.lo


def test_skt_send_max_rejects_negative_sizes():
    with pytest.raises(SettingError, match="skt_send_max: -1 is out of range; allowed: an integer 0..65535"):
        DEFAULT_SETTINGS.with_overrides(["skt_send_max=-1"])


def test_unknown_names_suggest_the_close_ones():
    with pytest.raises(SettingError, match=r"unknown Sysmac setting 'int_div_zro'; did you mean int_div_zero\?"):
        DEFAULT_SETTINGS.with_overrides(["int_div_zro=zero"])
    with pytest.raises(SettingError, match="--sysmac needs NAME=VALUE"):
        DEFAULT_SETTINGS.with_overrides(["int_div_zero"])
    with pytest.raises(TypeError):
        SysmacSettings(no_such_setting=1)


@pytest.mark.parametrize("name", [d.name for d in declarations() if d.table is not None])
def test_tables_are_checked_and_merged_from_toml(name):
    d = DECLARED[name]
    with pytest.raises(SettingError, match=f"{name} is a table"):
        DEFAULT_SETTINGS.with_overrides([f"{name}=1"])
    with pytest.raises(SettingError, match=f"{name}: unknown entry 'bogus'; allowed: {d.table.keys[0]}"):
        SysmacSettings(**{name: {"bogus": 1}})
    key = d.table.keys[0]
    with pytest.raises(SettingError, match=rf"{name}\.{key}: 'x' is not allowed; allowed: an integer"):
        DEFAULT_SETTINGS.with_table({name: {key: "x"}})
    changed = DEFAULT_SETTINGS.with_table({name: {key: 777}})
    assert getattr(changed, name) == {**d.default, key: 777}    # one entry changed, the rest kept


def test_enum_tables_need_distinct_values_where_the_code_needs_them():
    with pytest.raises(SettingError, match="byte_order_values: the values must differ"):
        SysmacSettings(byte_order_values={"_LOW_HIGH": 1, "_HIGH_LOW": 1})


def test_with_table_names_where_the_bad_value_came_from():
    with pytest.raises(SettingError, match=r"^stvm.toml: \[sysmac\]: int_div_zero: 'zeroo' is not allowed"):
        DEFAULT_SETTINGS.with_table({"int_div_zero": "zeroo"}, "stvm.toml: [sysmac]")
    with pytest.raises(SettingError, match=r"^\[sysmac\]: unknown Sysmac setting 'nope'"):
        DEFAULT_SETTINGS.with_table({"nope": 1})


def test_settings_are_a_stable_cache_key():
    # the compile cache hashes repr(settings): equal settings, equal text
    a = SysmacSettings(int_div_zero="zero", skt_error_codes={"timeout": 1})
    b = SysmacSettings(int_div_zero=DECLARED["int_div_zero"].kind.ZERO, skt_error_codes={"timeout": 1})
    assert a == b and repr(a) == repr(b) and repr(a) != repr(DEFAULT_SETTINGS)


# ---- meta: every setting is read, and read as its declared type ----------------------------------

def _code_files() -> list[Path]:
    files = sorted((ROOT / "stvm").rglob("*.py")) + sorted((ROOT / "emulator").rglob("*.py"))
    return [f for f in files if f != ROOT / "stvm" / "settings.py"]


def _attribute_reads() -> dict[str, list[str]]:
    reads: dict[str, list[str]] = {}
    for path in _code_files():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Attribute) and node.attr in DECLARED:
                reads.setdefault(node.attr, []).append(f"{path.relative_to(ROOT)}:{node.lineno}")
    return reads


def test_every_setting_is_read_outside_its_declaration():
    reads = _attribute_reads()
    unread = sorted(set(DECLARED) - set(reads))
    assert not unread, f"settings declared but never read: {unread}"


def _is_setting_read(node: ast.AST) -> bool:
    return (isinstance(node, ast.Attribute) and node.attr in DECLARED
            and "settings" in ast.unparse(node.value))


def test_reads_compare_with_the_declared_members_never_with_literals():
    offenders = []
    for path in _code_files():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Compare):
                sides = [node.left, *node.comparators]
                if any(_is_setting_read(s) for s in sides) and any(isinstance(s, ast.Constant) for s in sides):
                    offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}: {ast.unparse(node)}")
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "getattr" \
                    and len(node.args) >= 2 and isinstance(node.args[1], ast.Constant) \
                    and node.args[1].value in DECLARED:
                offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}: {ast.unparse(node)}")
    assert not offenders, "settings compared with free strings/numbers:\n" + "\n".join(offenders)


# ---- meta: every alternative changes something a test observes -----------------------------------

def _run_program(source: str, settings: SysmacSettings, paths: list[str], cycles: int = 1) -> Any:
    """An ST program's observable result: the values of `paths`, or its fault, or its errors."""
    try:
        vm = load_st(source, settings=settings).start()
    except stvm.LoadError as exc:
        return ("errors", [d.message for d in exc.diagnostics if d.is_error])
    try:
        vm.run(cycles=cycles)
    except stvm.RuntimeFault as fault:
        return ("fault", fault.message)
    return tuple(vm[p] for p in paths)


def _check_program(source: str, settings: SysmacSettings) -> list[tuple[str, str]]:
    from stvm.project import check
    _, diags, _ = check([write_st(source)], settings)
    return [(d.severity.value, d.message) for d in diags]


def probe_enum_default(settings):
    return _run_program("TYPE Color : (Red := 3, Green := 5); END_TYPE\n"
                        "PROGRAM Main VAR c : Color; END_VAR END_PROGRAM\n", settings, ["Main.c"])


def probe_fun_error_policy(settings):
    return _run_program("PROGRAM Main VAR u : UINT := 7; END_VAR u := STRING_TO_UINT('x'); END_PROGRAM\n",
                        settings, ["Main.u"])


def probe_array_oob(settings):
    return _run_program("PROGRAM Main VAR a : ARRAY[0..1] OF INT; i : INT := 2; n : INT; END_VAR\n"
                        "a[i] := 1; n := n + 1; END_PROGRAM\n", settings, ["Main.n"])


def probe_string_overflow(settings):
    return _run_program("PROGRAM Main VAR s : STRING[4]; t : STRING[9] := 'overflow'; END_VAR\n"
                        "s := t; END_PROGRAM\n", settings, ["Main.s"])


def probe_string_overflow_constant(settings):
    return _check_program("PROGRAM Main VAR s : STRING[4]; END_VAR s := 'overflow'; END_PROGRAM\n", settings)


def probe_dialect(settings):
    # names Sysmac reserves (`_`, `P_`) and one IEC refuses (`__`): errors or a run, by dialect
    return _run_program("PROGRAM Main VAR _rmp : INT; p_count : INT; a__b : INT; END_VAR\n"
                        "_rmp := 2; p_count := _rmp + 1; END_PROGRAM\n", settings, ["Main.p_count"])


def probe_dialect_twincat(settings):
    return _run_program("PROGRAM Main VAR s : T_MaxString; x : __XWORD := 16#FFFF_FFFF_FFFF; n : INT; END_VAR\n"
                        "s := 'abc'; n := LEN(s); END_PROGRAM\n", settings, ["Main.n", "Main.x"])


def probe_bare_enumerators(settings):
    return _check_program("TYPE Color : (Red, Green); END_TYPE\n"
                          "PROGRAM Main VAR c : Color; END_VAR c := Green; END_PROGRAM\n", settings)


def probe_invalid_dollar_escape(settings):
    return _run_program("PROGRAM Main VAR s : STRING; END_VAR s := 'a$Qb'; END_PROGRAM\n", settings, ["Main.s"])


def probe_double_quote_strings(settings):
    # only Sysmac reads double-quoted text as a STRING (elsewhere it is a WSTRING literal)
    return _check_program('PROGRAM Main VAR s : STRING; END_VAR s := "x"; END_PROGRAM\n',
                          replace(settings, dialect=Dialect.SYSMAC))


def probe_string_size(settings):
    return _run_program("PROGRAM Main VAR s : STRING[5]; END_VAR s := 'abcdefgh'; END_PROGRAM\n",
                        settings, ["Main.s"])


def probe_real_to_string_format(settings):
    return _run_program("PROGRAM Main VAR s : STRING; END_VAR s := REAL_TO_STRING(3.5); END_PROGRAM\n",
                        settings, ["Main.s"])


def probe_real_to_string_small(settings):
    return _run_program("PROGRAM Main VAR s : STRING; END_VAR s := LREAL_TO_STRING(LREAL#0.0099385); END_PROGRAM\n",
                        settings, ["Main.s"])


def probe_for_end_eval(settings):
    return _run_program("PROGRAM Main VAR i, n, count : INT; END_VAR n := 5; count := 0;\n"
                        "FOR i := 1 TO n DO n := n - 1; count := count + 1; END_FOR; END_PROGRAM\n",
                        settings, ["Main.count"])


def probe_int_div_zero(settings):
    return _run_program("PROGRAM Main VAR a : INT := 1; b : INT; q : INT := 5; d : INT := 5; "
                        "t : TIME := T#1s; END_VAR\nq := a / b; d := DIV(a, b); t := t / b; END_PROGRAM\n",
                        settings, ["Main.q", "Main.d", "Main.t"])


def probe_open_array_bounds(settings):
    return _run_program("FUNCTION First : DINT VAR_IN_OUT a : ARRAY[*] OF INT; END_VAR\n"
                        "First := a[1] * 100 + LOWER_BOUND(a, 1); END_FUNCTION\n"
                        "PROGRAM Main VAR arr : ARRAY[1..3] OF INT := [7, 8, 9]; f : DINT; END_VAR\n"
                        "f := First(arr); END_PROGRAM\n", settings, ["Main.f"])


def probe_subrange_check(settings):
    return _run_program("PROGRAM Main VAR p : INT(0..100) := 90; i : INT := 20; END_VAR\n"
                        "p := p + i; END_PROGRAM\n", settings, ["Main.p"])


Probe = Callable[[SysmacSettings], Any]
StdlibTest = str     # "tests/<path>.py::<test function>"

# (setting, alternative) -> a probe, or the test that asserts the alternative's behaviour.
# Numbers and tables have one key, "other": any other value.
OBSERVED: dict[tuple[str, str], Probe | StdlibTest] = {
    ("skt_progress_without_call", "cancel"):
        "tests/stdlib/test_sockets.py::test_request_cancelled_when_not_called_with_cancel_setting",
    ("enum_default", "zero"): probe_enum_default,
    ("fun_error_policy", "fault"): probe_fun_error_policy,
    ("array_oob", "skip_statement"): probe_array_oob,
    ("int_div_zero", "zero"): probe_int_div_zero,
    ("int_literal_type", "lint"):
        "tests/runtime/test_runtime_types.py::test_int_literal_type_lint_setting_removes_32_bit_wrap",
    ("string_length_unit", "bytes"): "tests/stdlib/test_strings.py::test_bytes_unit_counts_bytes",
    ("string_overflow", "error"): probe_string_overflow,
    ("dialect", "sysmac"): probe_dialect,
    ("dialect", "codesys"): probe_dialect,
    ("string_size", "with_nul"): probe_string_size,
    ("real_to_string_format", "c_exp"): probe_real_to_string_format,
    ("real_to_string_format", "digits15"): probe_real_to_string_small,
    ("pointer_overrun", "guard"):
        "tests/runtime/test_memory_overrun.py::test_the_setting_comes_from_the_command_line_and_the_manifest",
    ("dialect", "twincat"): probe_dialect_twincat,
    ("bare_enumerators", "require_type"): probe_bare_enumerators,
    ("dollar_n", "crlf"): "tests/syntax/test_syntax_literals.py::test_dollar_n_setting",
    ("invalid_dollar_escape", "literal"): probe_invalid_dollar_escape,
    ("double_quote_strings", "error"): probe_double_quote_strings,
    ("for_end_eval", "each"): probe_for_end_eval,
    ("open_array_bounds", "zero"): probe_open_array_bounds,
    ("subrange_check", "store"): probe_subrange_check,
    ("skt_send_copy", "at_service"):
        "tests/stdlib/test_sockets.py::test_send_copies_the_data_when_the_setting_says",
    ("skt_errorid_reset", "start_only"):
        "tests/stdlib/test_sockets.py::test_errorid_kept_after_error_clears_with_start_only",
    ("skt_min_latency_calls", "other"): "tests/stdlib/test_sockets.py::test_min_latency_calls",
    ("sockaddr_portno_type", "UDINT"): "tests/stdlib/test_sources.py::test_settings_rewrite_the_packaged_sources",
    ("connection_state_values", "other"):
        "tests/stdlib/test_sockets.py::test_status_uses_the_configured_enum_values",
    ("byte_order_values", "other"): "tests/stdlib/test_sources.py::test_system_enums_follow_the_settings",
    ("skt_connect_srcport0", "error"): "tests/stdlib/test_sockets.py::test_connect_bad_inputs",
    ("skt_socket_after_close", "zeroed"): "tests/stdlib/test_sockets.py::test_socket_output_after_close",
    ("skt_status_closed_handle", "error"):
        "tests/stdlib/test_sockets.py::test_status_of_closed_handle_error_setting",
    ("skt_send_size0", "error"): "tests/stdlib/test_sockets.py::test_send_size0_error_setting",
    ("skt_send_max", "other"): "tests/stdlib/test_sockets.py::test_send_max_setting",
    ("skt_rcv_timeout0", "error_if_empty"):
        "tests/stdlib/test_sockets.py::test_receive_timeout0_error_if_empty_setting",
    ("skt_rcv_timeout_unit_ns", "other"): "tests/stdlib/test_sockets.py::test_receive_timeout_unit_setting",
    ("skt_rcv_peer_closed", "error"): "tests/stdlib/test_sockets.py::test_receive_after_peer_close_error_setting",
    ("skt_error_codes", "other"): "tests/stdlib/test_sockets.py::test_error_codes_table_setting",
    ("toarybyte_string_model", "text"): "tests/stdlib/test_omron.py::test_string_models",
    ("toarybyte_string_model", "image"): "tests/stdlib/test_omron.py::test_string_models",
    ("toarybyte_wide_order", "word_swapped"): "tests/stdlib/test_omron.py::test_elementary_values",
    ("arytostring_oversize", "truncate"): "tests/stdlib/test_omron.py::test_aryto_string_oversize",
    ("rtfs_rounding", "half_even"): "tests/stdlib/test_omron.py::test_real_to_format_string_thesis_arguments",
    ("rtfs_negative_zero", "plus"):
        "tests/stdlib/test_omron.py::test_real_to_format_string_negative_zero_setting",
    ("rtfs_max_minlen", "other"): "tests/stdlib/test_omron.py::test_real_to_format_string_specials_and_limits",
    ("rtfs_max_decplace", "other"): "tests/stdlib/test_omron.py::test_real_to_format_string_specials_and_limits",
    ("byte_to_string_format", "hex_pad2"): "tests/stdlib/test_conversions.py::test_byte_to_string_formats",
    ("byte_to_string_format", "hex_nopad"): "tests/stdlib/test_conversions.py::test_byte_to_string_formats",
    ("stou_trailing", "ignore_blanks"): "tests/stdlib/test_conversions.py::test_string_to_uint_settings",
    ("stou_plus", "error"): "tests/stdlib/test_conversions.py::test_string_to_uint_settings",
    ("gettime_resolution_ns", "other"):
        "tests/stdlib/test_omron.py::test_get_time_is_start_dt_plus_virtual_time_at_1_ms",
    ("sectodt_range", "clamp"): "tests/stdlib/test_omron.py::test_sec_to_dt_and_back",
    ("timer_clock", "call_time"): "tests/stdlib/test_timers.py::test_ton_call_time_clock_uses_the_vm_hook",
    ("rtrig_first_call", "no_fire"): "tests/stdlib/test_st_blocks.py::test_settings_reach_the_generated_stdlib",
    ("ton_pt_below_et", "keep_timing"): "tests/stdlib/test_timers.py::test_ton_pt_lowered_below_et_keep_timing",
    ("ton_nonpositive_pt_et", "pt"): "tests/stdlib/test_timers.py::test_ton_nonpositive_pt",
    ("iec_pin_aliases", "off"): "tests/stdlib/test_sources.py::test_settings_rewrite_the_packaged_sources",
    ("string_result_overflow", "truncate"):
        "tests/stdlib/test_strings.py::test_result_over_1985_bytes_is_an_error_or_truncated",
    ("string_fn_range", "clamp"): "tests/stdlib/test_strings.py::test_position_clamped",
    ("concat_arity", "two_or_more"): "tests/stdlib/test_strings.py::test_concat_one_input_error_when_two_required",
    ("find_empty", "1"): "tests/stdlib/test_strings.py::test_find_empty_setting",
    ("max_array_elements", "other"): "tests/security/test_input_limits.py::test_the_array_limit_is_a_setting",
}

# settings whose probe needs more than the one alternative it is keyed by
EXTRA_PROBES = {("string_overflow", "error"): [probe_string_overflow_constant]}


def _alternatives(d: Declaration) -> list[str]:
    if d.choices:
        return [str(m.value) for m in d.choices if m is not d.default]
    return ["other"]


def test_the_table_covers_every_alternative_of_every_setting():
    wanted = {(d.name, alt) for d in declarations() for alt in _alternatives(d)}
    assert set(OBSERVED) == wanted, (sorted(wanted - set(OBSERVED)), sorted(set(OBSERVED) - wanted))


PROBED = [key for key, where in OBSERVED.items() if callable(where)]
REFERENCED = [key for key, where in OBSERVED.items() if not callable(where)]


@pytest.mark.parametrize("key", PROBED, ids=[f"{n}={v}" for n, v in PROBED])
def test_each_probed_alternative_changes_the_result(key):
    name, alternative = key
    member = next(m for m in DECLARED[name].choices if str(m.value) == alternative)
    other = SysmacSettings(**{name: member})
    for probe in [OBSERVED[key], *EXTRA_PROBES.get(key, [])]:
        default_result, other_result = probe(DEFAULT_SETTINGS), probe(other)
        assert default_result != other_result, (probe.__name__, default_result)


def _test_source(where: str) -> str | None:
    """The text of test function `path::name`, its decorators (parameters) included."""
    path, _, function = where.partition("::")
    text = (ROOT / path).read_text(encoding="utf-8")
    for node in ast.parse(text).body:
        if isinstance(node, ast.FunctionDef) and node.name == function:
            return "\n".join(ast.get_source_segment(text, x) or "" for x in [*node.decorator_list, node])
    return None


@pytest.mark.parametrize("key", REFERENCED, ids=[f"{n}={v}" for n, v in REFERENCED])
def test_each_referenced_test_exists_and_names_its_setting_and_value(key):
    name, alternative = key
    source = _test_source(OBSERVED[key])
    assert source is not None, f"{OBSERVED[key]} does not exist"
    assert name in source, f"{OBSERVED[key]} does not mention {name}"
    if alternative != "other":
        assert re.search(rf"\b{re.escape(alternative)}\b", source), f"{OBSERVED[key]} never uses {alternative!r}"


# ---- the docs table --------------------------------------------------------------------------------

def _shown(d: Declaration, value: Any) -> str:
    if isinstance(value, Enum):
        return f"`{value.value}`"
    if isinstance(value, dict):
        return ", ".join(f"`{k}`={v:#x}" if d.name == "skt_error_codes" else f"`{k}`={v}" for k, v in value.items())
    return f"`{value}`"


def readme_rows() -> list[str]:
    rows = ["| setting | sysmac.md | decides | default | alternatives |", "|---|---|---|---|---|"]
    for d in declarations():
        if d.choices:
            others = ", ".join(f"`{m.value}`" for m in d.choices if m is not d.default)
        elif d.table is not None:
            others = f"a table: `[sysmac.{d.name}]` in stvm.toml, or Python"
        else:
            others = f"an integer {d.lo}..{d.hi}"
        rows.append(f"| `{d.name}` | {d.spec} | {d.meaning.rstrip('.')} | {_shown(d, d.default)} | {others} |")
    return rows


def test_the_readme_settings_table_is_the_declarations():
    readme = (ROOT / "docs" / "sysmac_behaviours.md").read_text(encoding="utf-8").splitlines()
    start = readme.index("| setting | sysmac.md | decides | default | alternatives |")
    table = readme[start:start + len(DECLARED) + 2]
    expected = readme_rows()
    assert table == expected, "docs/sysmac_behaviours.md settings table is out of date; it should read:\n" + "\n".join(expected)
