"""stvm.syntax literal decoding: integers (based, grouped, typed), reals, TIME/DATE/TOD/DT, strings."""

from __future__ import annotations

import calendar

import pytest

from stvm.settings import SysmacSettings
from stvm.syntax import nodes as n
from stvm.syntax import parse_expression
from stvm.syntax.literals import LiteralError, decode_string, decode_time

NS = 1
US = 1_000
MS = 1_000_000
S = 1_000_000_000
M = 60 * S
H = 60 * M
D = 24 * H


def lit(text: str):
    node, diags = parse_expression(text)
    assert node is not None and not [d for d in diags if d.is_error], (text, diags)
    return node


@pytest.mark.parametrize(("text", "value"), [
    ("0", 0), ("42", 42), ("1_000", 1000), ("1_000_000", 1_000_000),
    ("16#FF", 255), ("16#ff", 255), ("16#FF_FF", 65535), ("2#1010", 10), ("2#1111_0000", 240),
    ("8#17", 15), ("8#777", 511), ("9223372036854775807", 2**63 - 1),
])
def test_integer_literals(text, value):
    node = lit(text)
    assert isinstance(node, n.IntLiteral) and node.value == value


@pytest.mark.parametrize(("text", "value"), [
    ("1.5", 1.5), ("0.1", 0.1), ("1.5e3", 1500.0), ("1.5E3", 1500.0), ("2E-2", 0.02), ("1e10", 1e10),
    ("1_000.5", 1000.5), ("3.0e+2", 300.0),
])
def test_real_literals(text, value):
    node = lit(text)
    assert isinstance(node, n.RealLiteral) and node.value == value


@pytest.mark.parametrize(("text", "prefix", "body"), [
    ("INT#5", "INT", "5"), ("INT#-5", "INT", "-5"), ("REAL#1.5", "REAL", "1.5"),
    ("LREAL#-1.5e3", "LREAL", "-1.5e3"), ("BYTE#16#0A", "BYTE", "16#0A"), ("UINT#5", "UINT", "5"),
    ("BOOL#1", "BOOL", "1"), ("DINT#2#1010", "DINT", "2#1010"),
])
def test_typed_literals_keep_their_type_name(text, prefix, body):
    node = lit(text)
    assert isinstance(node, n.HashLiteral) and node.prefix == (prefix,) and node.text == body


@pytest.mark.parametrize(("text", "ns"), [
    ("T#0s", 0), ("T#1s", S), ("T#1000ms", S), ("T#1s500ms", S + 500 * MS),
    ("T#1h2m3s4ms5us6ns", H + 2 * M + 3 * S + 4 * MS + 5 * US + 6 * NS),
    ("TIME#1m30s", 90 * S), ("t#1.5s", 1500 * MS), ("T#1.5h", 90 * M), ("T#2d", 2 * D),
    ("T#1d2h", D + 2 * H), ("T#-1.5s", -1500 * MS), ("T#-250ms", -250 * MS), ("T#1_000ms", S),
    ("T#500us", 500 * US), ("T#0.5ms", 500 * US), ("T#10ns", 10), ("T#1m", M), ("T#1ms", MS),
])
def test_time_literals(text, ns):
    node = lit(text)
    assert isinstance(node, n.TimeLiteral) and node.value_ns == ns
    assert decode_time(text) == ns


@pytest.mark.parametrize("text", ["T#5x", "T#5", "T#1s2", "T#"])
def test_malformed_time_literals(text):
    with pytest.raises(LiteralError):
        decode_time(text)


def _epoch_ns(*parts) -> int:
    return calendar.timegm(parts + (0,) * (6 - len(parts))) * S


@pytest.mark.parametrize(("text", "ns"), [
    ("D#1970-01-01", 0),
    ("D#2024-02-29", _epoch_ns(2024, 2, 29)),
    ("DATE#2000-01-01", _epoch_ns(2000, 1, 1)),
    ("TOD#12:34:56", (12 * 3600 + 34 * 60 + 56) * S),
    ("TOD#12:34:56.789", (12 * 3600 + 34 * 60 + 56) * S + 789 * MS),
    ("TIME_OF_DAY#00:00:01", S),
    ("DT#2024-01-02-03:04:05", _epoch_ns(2024, 1, 2, 3, 4, 5)),
    ("DATE_AND_TIME#1970-01-01-00:00:00", 0),
    ("DT#2106-02-06-23:59:59", _epoch_ns(2106, 2, 6, 23, 59, 59)),
])
def test_date_and_time_of_day_literals(text, ns):
    node = lit(text)
    assert isinstance(node, n.TimeLiteral) and node.value_ns == ns


# ---------------------------------------------------------------- strings
DEFAULT = SysmacSettings()


@pytest.mark.parametrize(("text", "value"), [
    ("''", b""),
    ("'abc'", b"abc"),
    ("'$$'", b"$"),
    ("'$''", b"'"),
    ("'$L$l'", b"\n\n"),
    ("'$R$r'", b"\r\r"),
    ("'$P'", b"\f"),
    ("'$T'", b"\t"),
    ("'$N'", b"\n"),                                   # sysmac dollar_n default: LF
    ("'$41$4a$4A'", b"AJJ"),
    ("'$00'", b""),                                    # a value ends at the first 16#00
    ("'ab$00cd'", b"ab"),
    ("'$$TMSTA,2,00,*41$R$L'", b"$TMSTA,2,00,*41\r\n"),  # sysmac.md 3 #7: 17 bytes
    ("'\"'", b'"'),
    ("'ü'", "ü".encode()),
])
def test_string_escapes(text, value):
    decoded, warnings = decode_string(text, DEFAULT)
    assert decoded == value and not warnings


def test_thesis_frame_is_17_bytes():
    assert len(decode_string("'$$TMSTA,2,00,*41$R$L'", DEFAULT)[0]) == 17


def test_dollar_n_setting():
    assert decode_string("'$N'", SysmacSettings(dollar_n="crlf"))[0] == b"\r\n"


@pytest.mark.parametrize("text", ["'$Q'", "'$R$QueueTag('", "'$G'", "'$4'"])
def test_invalid_escapes_are_errors_by_default(text):
    with pytest.raises(LiteralError):
        decode_string(text, DEFAULT)


def test_double_quoted_strings_are_accepted_as_string_in_sysmac():
    node, diags = parse_expression('"a$"b"', settings=SysmacSettings(dialect="sysmac"))
    assert isinstance(node, n.StringLiteral) and node.value == b'a"b'
    assert diags and all(not d.is_error for d in diags)   # a warning (double_quote_strings)


def test_string_literal_node():
    node = lit("'it$'s'")
    assert isinstance(node, n.StringLiteral) and node.value == b"it's"


@pytest.mark.parametrize(("text", "value"), [("TRUE", True), ("false", False), ("True", True)])
def test_bool_literals(text, value):
    node = lit(text)
    assert isinstance(node, n.BoolLiteral) and node.value is value


@pytest.mark.parametrize("dialect", ["iec", "codesys", "twincat"])
def test_double_quoted_text_is_a_wstring_literal_outside_sysmac(dialect):
    settings = SysmacSettings().with_table({"dialect": dialect}, "test")
    node, diags = parse_expression('"Grü$00DF$"e😀"', settings=settings)
    assert isinstance(node, n.StringLiteral) and node.double_quoted and not diags
    assert node.value == 'Grüß"e\ud83d\ude00'   # UTF-16 code units, one Python character each


def test_a_wstring_escape_needs_four_hex_digits():
    settings = SysmacSettings().with_table({"dialect": "iec"}, "test")
    _, diags = parse_expression('"$41"', settings=settings)
    assert [d for d in diags if d.is_error and "invalid escape '$4' in WSTRING literal" in d.message]


def test_a_surrogate_escape_in_a_sysmac_string_is_a_diagnostic():
    with pytest.raises(LiteralError, match="half of a UTF-16 surrogate pair"):
        decode_string('"$D800"', SysmacSettings())
