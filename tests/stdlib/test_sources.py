"""The stdlib's ST interface: every native declaration has an implementation with matching
flags and arity, settings regenerate what depends on them, and the core accepts it all."""

from __future__ import annotations

import inspect
import re

import pytest

from stdlib_helpers import make_ctx  # noqa: F401  (puts the checkout on sys.path)
from stvm.semantics import analyze
from stvm.settings import DEFAULT_SETTINGS, SysmacSettings
from stvm.stdlib import stdlib_sources
from stvm.stdlib.registry import NATIVE_FBS, NATIVE_FUNCTIONS
from stvm.syntax.parser import parse_text

POU = re.compile(r"(?:\{([^}]*)\}\s*)?\b(FUNCTION_BLOCK|FUNCTION)\s+(\w+)(.*?)\bEND_\2\b", re.S)
BLOCK = re.compile(r"\b(VAR_INPUT|VAR_IN_OUT|VAR_OUTPUT|VAR)\b(.*?)\bEND_VAR\b", re.S)
COMMENT = re.compile(r"\(\*.*?\*\)", re.S)


def declarations(settings: SysmacSettings = DEFAULT_SETTINGS):
    """(pragma words, kind, name, {section: [names]}) of every POU in the stdlib sources."""
    found = []
    for _, text in stdlib_sources(settings):
        text = COMMENT.sub("", text)
        for pragma, kind, name, body in POU.findall(text):
            sections: dict[str, list[str]] = {}
            for section, decls in BLOCK.findall(body):
                names = [d.split(":")[0].strip() for d in decls.split(";") if ":" in d]
                sections.setdefault(section, []).extend(names)
            found.append((pragma.split(), kind, name, sections))
    return found


def _every_dialects_declarations():
    # a vendor's platform library (TwinCAT's ADSLOG*, ...) is in the stdlib of its dialect only
    from stvm.settings import Dialect
    found = []
    for dialect in Dialect:
        found += declarations(DEFAULT_SETTINGS.with_overrides([f"dialect={dialect.value}"]))
    return found


def test_every_native_declaration_has_an_implementation_and_back():
    declared_functions, declared_fbs = set(), set()
    for words, kind, name, _ in _every_dialects_declarations():
        if words and words[0] == "native":
            (declared_fbs if kind == "FUNCTION_BLOCK" else declared_functions).add(name.upper())
    assert declared_functions == set(NATIVE_FUNCTIONS)
    assert declared_fbs == set(NATIVE_FBS)


def test_pragma_words_match_the_registry_flags():
    for words, kind, name, _ in declarations():
        if kind != "FUNCTION" or not words or words[0] != "native":
            continue
        native = NATIVE_FUNCTIONS[name.upper()]
        assert ("generic" in words, "variadic" in words, "typed" in words) == \
            (native.generic, native.variadic, native.typed), name


def test_function_arity_matches_the_declaration():
    for words, kind, name, sections in declarations():
        if kind != "FUNCTION" or not words or words[0] != "native":
            continue
        native = NATIVE_FUNCTIONS[name.upper()]
        declared = len(sections.get("VAR_INPUT", [])) + len(sections.get("VAR_IN_OUT", []))
        parameters = list(inspect.signature(native.impl).parameters.values())
        fixed = 1 + native.generic + native.typed
        if any(p.kind == p.VAR_POSITIONAL for p in parameters):
            assert native.variadic, name
            continue
        assert len(parameters) - fixed == declared, name


def test_socket_fbs_declare_the_protocol_pins():
    for words, kind, name, sections in declarations():
        if name.startswith("Skt"):
            assert sections["VAR_INPUT"][0] == "Execute"
            assert sections["VAR_OUTPUT"][:4] == ["Done", "Busy", "Error", "ErrorID"]


def source(name: str, settings: SysmacSettings = DEFAULT_SETTINGS) -> str:
    return dict(stdlib_sources(settings))[f"<stdlib>/{name}"]


def test_system_enums_follow_the_settings():
    default = source("system_types.st")
    assert "_eBYTE_ORDER : (_LOW_HIGH := 0, _HIGH_LOW := 1);" in default
    assert "_CLOSED := 0, _LISTEN := 1," in default and "_TIME_WAIT := 10" in default
    other = SysmacSettings(byte_order_values={"_LOW_HIGH": 1, "_HIGH_LOW": 2},
                           connection_state_values={"_CLOSED": 1, "_ESTABLISHED": 2, "_CLOSE_WAIT": 3})
    text = source("system_types.st", other)
    assert "(_LOW_HIGH := 1, _HIGH_LOW := 2)" in text
    assert "(_CLOSED := 1, _ESTABLISHED := 2, _CLOSE_WAIT := 3)" in text


def test_settings_rewrite_the_packaged_sources():
    assert "M : BOOL := FALSE;" in source("iec_standard.st")
    assert "M : BOOL := TRUE;" in source("iec_standard.st", SysmacSettings(rtrig_first_call="no_fire"))
    assert "{alias Reset=R}" in source("iec_standard.st")
    assert "\n{alias" not in source("iec_standard.st", SysmacSettings(iec_pin_aliases="off"))
    assert "PortNo : UINT;" in source("sockets.st")
    assert "PortNo : UDINT;" in source("sockets.st", SysmacSettings(sockaddr_portno_type="UDINT"))


def test_thesis_names_are_all_available():
    names = {name.upper() for _, _, name, _ in declarations()}
    for needed in ["R_TRIG", "F_TRIG", "TON", "SKTTCPCONNECT", "SKTCLEARBUF", "SKTGETTCPSTATUS",
                   "SKTTCPSEND", "SKTTCPRCV", "SKTCLOSE", "CONCAT", "LEN", "FIND", "TOARYBYTE",
                   "ARYTOSTRING", "REALTOFORMATSTRING", "BYTE_TO_STRING", "UINT_TO_STRING",
                   "INT_TO_STRING", "STRING_TO_UINT", "GETTIME", "SECTODT", "NANOSECTOTIME"]:
        assert needed in names, needed


@pytest.mark.parametrize("settings", [
    DEFAULT_SETTINGS,
    SysmacSettings(rtrig_first_call="no_fire", iec_pin_aliases="off", sockaddr_portno_type="UDINT"),
], ids=["default", "alternatives"])
def test_the_core_accepts_the_stdlib(settings):
    units, problems = [], []
    for path, text in stdlib_sources(settings):
        unit, diagnostics = parse_text(text, path, settings)
        units.append(unit)
        problems += diagnostics
    problems += analyze(units, settings, NATIVE_FUNCTIONS).diagnostics
    assert [f"{d.span.file}:{d.span.line}: {d.message}" for d in problems] == []
