"""The standard library: IEC 61131-3 POUs, Omron Sysmac instructions and the TCP socket FBs.

Every POU has an ST declaration (the `.st` files here plus generated text), so the checker treats
library calls like user calls; native ones carry `{native}` and are implemented in the Python
modules imported below, which fill `stvm.stdlib.registry` on import.

`stdlib_sources(settings)` returns the (display path, ST text) pairs to load before user code.
Parts of the text depend on UNCERTAIN settings (sysmac.md 9), so a run with other settings must
regenerate them: the `_eCONNECTION_STATE`/`_eBYTE_ORDER` enumerator values
(`connection_state_values`, `byte_order_values`), the PortNo type (`sockaddr_portno_type`),
R_TRIG's first call (`rtrig_first_call`) and the Omron pin aliases (`iec_pin_aliases`).
"""

from __future__ import annotations

import re

import importlib
from functools import lru_cache
from importlib import resources

from stvm.dialects import allows
from stvm.settings import DEFAULT_SETTINGS, Dialect, IecPinAliases, RtrigFirstCall, SockaddrPortnoType, SysmacSettings

from stvm.stdlib.registry import NATIVE_FBS, NATIVE_FUNCTIONS, native_fb, native_function

# Importing the implementation modules registers the natives: `load_natives()` imports them all
# (the checker needs every declaration; `stdlib_sources` calls it), a VM from the cache imports
# only the modules its program calls into (`Project.native_modules`). lazy: start-up
IMPLEMENTATIONS = ("conversions", "numeric", "omron", "sockets", "strings", "timefns", "timers", "bcd", "tc2_system",
                   "tc2_memory", "sys_file", "cds_operators", "sys_mem", "tc2_utilities")
_SOCKET_NAMES = ("RealTcpTransport", "SocketTable", "Transport", "make_default_transport")


def natives_for(project):
    """(native functions, native FBs) for a VM of `project` (what `Project.start` passes it)."""
    complete = _register_natives(project, NATIVE_FUNCTIONS, NATIVE_FBS)
    return NATIVE_FUNCTIONS, (NATIVE_FBS if complete else _NativeFBs(NATIVE_FBS))


def _register_natives(project, functions, fbs) -> bool:
    """Import the stdlib modules with the natives `project` calls. A project from the cache names
    them (`native_modules`, the modules of the natives its generated code calls): only those are
    imported, so `stvm run` pays only for what the program uses; returns False then (the registry
    may lack natives the program never calls). Any other project gets every module: True."""
    lowered = project.lowered
    if getattr(project, "natives_known", False):
        for module in project.native_modules:
            if module.startswith("stvm.stdlib."):
                importlib.import_module(module)
        return False
    if not (all(k in functions for k in lowered.natives.values()) and all(k in fbs for k in lowered.native_fbs.values())):
        load_natives()
    return True


class _NativeFBs:
    """`_NATIVE_FB` of a VM whose registry holds only the natives its program calls: a native FB
    that is not there yet (an FB the program instantiates) loads the rest of the stdlib."""

    partial = True   # the VM does not require every declared native to be registered

    def __init__(self, registry) -> None:
        self._registry = registry

    def __getitem__(self, key):
        try:
            return self._registry[key]
        except KeyError:
            load_natives()
            return self._registry[key]


def load_natives() -> None:
    """Register every native function and FB (import all the implementation modules)."""
    for name in IMPLEMENTATIONS:
        importlib.import_module(f"stvm.stdlib.{name}")


def __getattr__(name: str):
    if name in _SOCKET_NAMES:
        from stvm.stdlib import sockets   # lazy: start-up
        return getattr(sockets, name)
    raise AttributeError(name)

ST_FILES = ("iec_standard.st", "iec_functions.st", "omron.st", "sockets.st")
DISPLAY_PREFIX = "<stdlib>/"


@lru_cache(maxsize=None)
def _packaged_text(name: str) -> str:
    return resources.files(__package__).joinpath(name).read_text(encoding="utf-8")


def _rewrite(text: str, marker_line: str, replacement: str) -> str:
    """Replace one marked line of a packaged file (it must be there: a guard against drift)."""
    if marker_line not in text:
        raise AssertionError(f"stdlib source lost the line {marker_line!r}")
    return text.replace(marker_line, replacement)


TWINCAT_LIBRARIES = ("tc2_standard.st", "tc2_system.st", "tc2_utilities.st", "type_classes.st", "tc2_memory.st",
                     "sys_file.st", "tc3_module.st")
# CODESYS V3 operators beyond IEC's (TIME(), TRUNC_INT, …), in CODESYS and in TwinCAT (built on it)
CODESYS_OPERATORS = "cds_operators.st"
CODESYS_UTIL = "cds_util.st"     # the CODESYS Util library (BLINK, HYSTERESIS, RAMP_*, CHARCURVE, …), CODESYS only
# namespaces of the platform libraries, reached as `IBaseLibrary.TypeClass.TYPE_INT` (stvm/libraries.py)
TWINCAT_NAMESPACES = ("IBaseLibrary", "__SYSTEM", "SysFile", "SysDir", "SysTypes", "CmpErrors")
# CODESYS V3 has the same type classes and ANY descriptor (CODESYS online help "ANY": the compiler
# passes `__SYSTEM.AnyType`; Base Interfaces library "TypeClass"), not Beckhoff's Tc2 libraries;
# then its Util and SysMem libraries
CODESYS_LIBRARIES = ("type_classes.st", CODESYS_UTIL, "sys_mem.st")
CODESYS_NAMESPACES = ("IBaseLibrary", "__SYSTEM")

# Beckhoff Tc2_Standard names the inputs of the string functions STR/STR1/STR2/SIZE/LEN/POS
# (infosys.beckhoff.com, Tc2_Standard "CONCAT": `STR1 : STRING(255); STR2 : STRING(255);`, and
# the pages of LEN, LEFT, RIGHT, MID, FIND, INSERT, DELETE, REPLACE): under the twincat dialect
# they are aliases of the IEC inputs, so `CONCAT(STR1 := a, STR2 := b)` calls the same function.
TC2_STANDARD_PINS = {
    "CONCAT": "STR1=In1 STR2=In2", "LEN": "STR=In", "LEFT": "STR=In SIZE=L", "RIGHT": "STR=In SIZE=L",
    "MID": "STR=In LEN=L POS=P", "FIND": "STR1=In1 STR2=In2", "INSERT": "STR1=In1 STR2=In2 POS=P",
    "DELETE": "STR=In LEN=L POS=P", "REPLACE": "STR1=In1 STR2=In2 LEN=L POS=P",
}


_OMRON_ROUNDING = tuple(
    f"{{native generic}}\nFUNCTION {name} : ANY_INT\nVAR_INPUT\n    In : ANY_REAL;\nEND_VAR\nEND_FUNCTION\n"
    for name in ("Round", "RoundUp"))


def _tc2_standard_pins(text: str) -> str:
    for function, pins in TC2_STANDARD_PINS.items():
        marker = f"\nFUNCTION {function} : "
        text = _rewrite(text, marker, f"\n{{alias {pins}}}{marker}")
    return text


def _apply_settings(name: str, text: str, settings: SysmacSettings) -> str:
    if name == "iec_functions.st" and allows(settings.dialect, "shift_any_integer"):
        # TwinCAT/CODESYS shift and rotate any integer, not only bit strings (stvm/dialects.py)
        text = _rewrite(text, "IN : ANY_BIT; (* dialect: shift_any_integer *)",
                        "IN : ANY_BIT_OR_INT; (* dialect: shift_any_integer *)")
        text = re.sub(r"FUNCTION (SHL|SHR|ROL|ROR) : ANY_BIT\n", r"FUNCTION \1 : ANY_BIT_OR_INT\n", text)
        # and the count may be a bit string: CODESYS's and Beckhoff's own examples shift by a BYTE
        # (CODESYS help "Operator: SHL": `n : BYTE := 2; erg_byte := SHL(in_byte, n);`)
        text = text.replace("    N : ANY_INT;\n", "    N : ANY_BIT_OR_INT;\n")
    if name == "iec_functions.st" and settings.dialect in (Dialect.TWINCAT, Dialect.CODESYS):
        # EXPT's base may be any number (CODESYS help and Beckhoff Infosys "EXPT": "numeric base
        # data types"; `EXPT(7, 2)` is 49.0); its result is then an LREAL (numeric._power_type)
        text = _rewrite(text, "FUNCTION EXPT : ANY_REAL\nVAR_INPUT\n    IN1 : ANY_REAL;\n",
                        "FUNCTION EXPT : ANY_REAL\nVAR_INPUT\n    IN1 : ANY_NUM;\n")
    if name == "iec_functions.st" and settings.dialect in (Dialect.TWINCAT, Dialect.CODESYS):
        # Round and RoundUp are Omron instructions: TwinCAT and CODESYS have none, and projects
        # for them declare their own ROUND (OSCAT BASIC does); names are not case-sensitive
        for block in _OMRON_ROUNDING:
            text = _rewrite(text, block, "")
    if name == "iec_functions.st" and settings.dialect is Dialect.TWINCAT:
        text = _tc2_standard_pins(text)
    if name == "iec_standard.st":
        if settings.rtrig_first_call is RtrigFirstCall.NO_FIRE:
            # M starting TRUE makes a first call with CLK TRUE see no rising edge
            text = _rewrite(text, "M : BOOL := FALSE; (* sysmac: rtrig_first_call *)",
                            "M : BOOL := TRUE; (* sysmac: rtrig_first_call = no_fire *)")
        if settings.iec_pin_aliases is IecPinAliases.OFF:
            text = "\n".join(line for line in text.splitlines()
                             if not line.startswith("{alias"))
    if name == "sockets.st" and settings.sockaddr_portno_type is not SockaddrPortnoType.UINT:
        text = _rewrite(text, "PortNo : UINT; (* sysmac: sockaddr_portno_type *)",
                        f"PortNo : {settings.sockaddr_portno_type.value}; "
                        "(* sysmac: sockaddr_portno_type *)")
    return text


def _enum_declaration(name: str, values: dict[str, int], setting: str) -> str:
    members = ", ".join(f"{member} := {value}"
                        for member, value in sorted(values.items(), key=lambda item: item[1]))
    return f"(* from SysmacSettings.{setting} *)\nTYPE\n    {name} : ({members});\nEND_TYPE\n"


def system_types_source(settings: SysmacSettings = DEFAULT_SETTINGS) -> str:
    """The Omron system enums whose values are UNCERTAIN settings (sysmac.md 5)."""
    return "\n".join([
        "(* Generated by stvm.stdlib: Omron system enums (sysmac.md 5). *)",
        _enum_declaration("_eCONNECTION_STATE", settings.connection_state_values,
                          "connection_state_values"),
        _enum_declaration("_eBYTE_ORDER", settings.byte_order_values, "byte_order_values"),
    ])


def stdlib_sources(settings: SysmacSettings = DEFAULT_SETTINGS) -> list[tuple[str, str]]:
    """(display path, ST text) of every stdlib source, packaged and generated."""
    load_natives()
    from stvm.stdlib import bcd, conversions   # lazy: start-up
    from stvm.stdlib.counters import typed_counters_source   # lazy: start-up
    sources = [(f"{DISPLAY_PREFIX}system_types.st", system_types_source(settings))]
    for name in ST_FILES:
        sources.append((DISPLAY_PREFIX + name, _apply_settings(name, _packaged_text(name), settings)))
    sources.append((f"{DISPLAY_PREFIX}conversions.st", conversions.conversion_declarations()))
    iec_standard = _apply_settings("iec_standard.st", _packaged_text("iec_standard.st"), settings)
    sources.append((f"{DISPLAY_PREFIX}typed_counters.st", typed_counters_source(iec_standard)))
    sources.append((f"{DISPLAY_PREFIX}bcd.st", bcd.bcd_declarations()))
    if settings.dialect in (Dialect.TWINCAT, Dialect.CODESYS):
        sources.append((DISPLAY_PREFIX + CODESYS_OPERATORS, _packaged_text(CODESYS_OPERATORS)))
    if settings.dialect is Dialect.TWINCAT:   # vendor extras exist only in their dialect
        sources.append((f"{DISPLAY_PREFIX}twincat_types.st", _packaged_text("twincat_types.st")))
        # the Beckhoff platform libraries (docs/platform_libraries.md)
        for name in TWINCAT_LIBRARIES:
            sources.append((DISPLAY_PREFIX + name, _packaged_text(name)))
    elif settings.dialect is Dialect.CODESYS:
        for name in CODESYS_LIBRARIES:
            sources.append((DISPLAY_PREFIX + name, _packaged_text(name)))
    return sources


__all__ = ["stdlib_sources", "system_types_source", "NATIVE_FUNCTIONS", "NATIVE_FBS",
           "native_function", "native_fb", "Transport", "SocketTable", "RealTcpTransport",
           "make_default_transport"]
