"""String functions (sysmac.md 7): 1-based character positions, range errors, result limit."""

from __future__ import annotations

import pytest

from stdlib_helpers import call, make_ctx
from stvm.runtime.values import FunctionError


@pytest.mark.parametrize(("name", "args", "result"), [
    # the spec's examples
    ("CONCAT", (b"AB", b"CD", b"E"), b"ABCDE"),
    ("LEN", (b"ASTRING",), 7),
    ("LEFT", (b"ASTR", 3), b"AST"),
    ("RIGHT", (b"ASTR", 3), b"STR"),
    ("MID", (b"ASTR", 2, 2), b"ST"),
    ("FIND", (b"ABCBC", b"BC"), 2),
    ("INSERT", (b"ABC", b"XY", 2), b"ABXYC"),
    ("DELETE", (b"ABXYC", 2, 3), b"ABC"),
    ("REPLACE", (b"ABCDE", b"X", 2, 3), b"ABXE"),
    # edges
    ("CONCAT", (b"", b""), b""),
    ("LEN", (b"",), 0),
    ("LEFT", (b"AB", 5), b"AB"),
    ("LEFT", (b"AB", 0), b""),
    ("RIGHT", (b"AB", 5), b"AB"),
    ("RIGHT", (b"AB", 0), b""),
    ("MID", (b"ASTR", 10, 3), b"TR"),          # L past the end takes the rest
    ("MID", (b"ASTR", 0, 4), b""),
    ("FIND", (b"ABC", b"X"), 0),
    ("FIND", (b"", b"X"), 0),
    ("FIND", (b"ABC", b""), 0),                # find_empty
    ("FIND", (b"abc", b"B"), 0),               # case-sensitive
    ("FIND", (b"AB", b"ABC"), 0),
    ("INSERT", (b"ABC", b"XY", 0), b"XYABC"),
    ("INSERT", (b"ABC", b"XY", 3), b"ABCXY"),
    ("INSERT", (b"", b"XY", 0), b"XY"),
    ("DELETE", (b"ABC", 10, 2), b"A"),
    ("DELETE", (b"ABC", 0, 1), b"ABC"),
    ("REPLACE", (b"ABC", b"", 1, 2), b"AC"),
    ("REPLACE", (b"ABC", b"XYZ", 0, 1), b"XYZABC"),
])
def test_string_function(name, args, result):
    assert call(name, make_ctx(), *args) == result


@pytest.mark.parametrize(("name", "args"), [
    ("MID", (b"ASTR", 1, 0)),
    ("MID", (b"ASTR", 1, 5)),
    ("MID", (b"", 1, 1)),
    ("INSERT", (b"ABC", b"X", 4)),
    ("DELETE", (b"ABC", 1, 0)),
    ("DELETE", (b"ABC", 1, 4)),
    ("REPLACE", (b"ABC", b"X", 1, 4)),
    ("REPLACE", (b"", b"X", 0, 1)),
])
def test_position_out_of_range_is_an_instruction_error(name, args):
    with pytest.raises(FunctionError):
        call(name, make_ctx(), *args)


@pytest.mark.parametrize(("name", "args", "result"), [
    ("MID", (b"ASTR", 2, 9), b"R"),             # P clamped to LEN
    ("MID", (b"ASTR", 2, 0), b"AS"),
    ("INSERT", (b"ABC", b"X", 9), b"ABCX"),
    ("DELETE", (b"ABC", 1, 9), b"AB"),
])
def test_position_clamped(name, args, result):
    assert call(name, make_ctx(string_fn_range="clamp"), *args) == result


def test_utf8_positions_count_characters():
    ctx = make_ctx()
    text = "aé€b".encode()           # 1 + 2 + 3 + 1 bytes, 4 characters
    assert call("LEN", ctx, text) == 4
    assert call("LEFT", ctx, text, 2) == "aé".encode()
    assert call("RIGHT", ctx, text, 2) == "€b".encode()
    assert call("MID", ctx, text, 1, 3) == "€".encode()
    assert call("FIND", ctx, text, "b".encode()) == 4
    assert call("INSERT", ctx, text, b"X", 2) == "aéX€b".encode()
    assert call("DELETE", ctx, text, 2, 2) == b"ab"


def test_invalid_utf8_byte_counts_one():
    ctx = make_ctx()
    assert call("LEN", ctx, b"A\xffB\xe2\x82") == 5
    assert call("MID", ctx, b"A\xffB", 1, 2) == b"\xff"  # bytes come back unchanged


def test_bytes_unit_counts_bytes():
    ctx = make_ctx(string_length_unit="bytes")
    text = "aé".encode()
    assert call("LEN", ctx, text) == 3
    assert call("LEFT", ctx, text, 2) == b"a\xc3"


def test_concat_many_inputs_and_limits():
    ctx = make_ctx()
    assert call("CONCAT", ctx, *[b"x"] * 32) == b"x" * 32
    with pytest.raises(FunctionError):
        call("CONCAT", ctx, *[b"x"] * 33)


def test_concat_one_input_warns_once():
    ctx = make_ctx()
    assert call("CONCAT", ctx, b"AB") == b"AB"
    assert call("CONCAT", ctx, b"CD") == b"CD"
    assert len(ctx.warnings) == 1


def test_concat_one_input_error_when_two_required():
    with pytest.raises(FunctionError):
        call("CONCAT", make_ctx(concat_arity="two_or_more"), b"AB")


def test_result_over_1985_bytes_is_an_error_or_truncated():
    with pytest.raises(FunctionError):
        call("CONCAT", make_ctx(), b"a" * 1000, b"b" * 986)
    assert call("CONCAT", make_ctx(), b"a" * 1000, b"b" * 985) == b"a" * 1000 + b"b" * 985
    truncated = call("CONCAT", make_ctx(string_result_overflow="truncate"), b"a" * 1000, b"b" * 1000)
    assert truncated == b"a" * 1000 + b"b" * 985
    with pytest.raises(FunctionError):
        call("INSERT", make_ctx(), b"a" * 1985, b"b", 0)


def test_truncation_keeps_utf8_characters_whole():
    ctx = make_ctx(string_result_overflow="truncate")
    result = call("CONCAT", ctx, b"a" * 1984, "é".encode())
    assert result == b"a" * 1984  # the 2-byte é does not fit in the last byte


@pytest.mark.parametrize("value", [0, 1])
def test_find_empty_setting(value):
    assert call("FIND", make_ctx(find_empty=value), b"ABC", b"") == value
