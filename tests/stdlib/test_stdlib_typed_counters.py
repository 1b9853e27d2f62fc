"""Typed counters (IEC 61131-3 ed. 3 table 45): CTU_<T>, CTD_<T>, CTUD_<T> for INT, DINT, LINT,
UDINT, ULINT count like CTU/CTD/CTUD with PV/CV of that type and stop at that type's limits."""

from __future__ import annotations

import pytest

from core_helpers import check_text, start_st
from stvm.stdlib.counters import TYPED


def _pulses(vm, cycles: int) -> None:
    for _ in range(cycles):
        vm["Main.tick"] = True
        vm.run(cycles=1)
        vm["Main.tick"] = False
        vm.run(cycles=1)


@pytest.mark.parametrize("type_name", TYPED)
def test_every_typed_counter_counts(type_name):
    vm = start_st(f"""
PROGRAM Main
VAR u : CTU_{type_name}; d : CTD_{type_name}; ud : CTUD_{type_name}; tick, load : BOOL; END_VAR
u(CU := tick, PV := 3);
d(CD := tick, LD := load, PV := 2);
ud(CU := tick, CD := FALSE, PV := 2);
END_PROGRAM
""")
    vm["Main.load"] = True
    vm.run(cycles=1)
    vm["Main.load"] = False
    _pulses(vm, 3)
    assert (vm["Main.u.CV"], vm["Main.u.Q"]) == (3, True)
    assert vm["Main.d.Q"] is True
    assert (vm["Main.ud.CV"], vm["Main.ud.QU"]) == (3, True)


def test_ctu_dint_counts_past_the_int_limit():
    vm = start_st("""
PROGRAM Main
VAR c : CTU_DINT; tick : BOOL; END_VAR
c(CU := tick, PV := 40000);
END_PROGRAM
""")
    vm.run(cycles=1)
    vm["Main.c.CV"] = 39999
    _pulses(vm, 2)
    assert (vm["Main.c.CV"], vm["Main.c.Q"]) == (40001, True)


def test_unsigned_down_counter_stops_at_zero():
    vm = start_st("""
PROGRAM Main
VAR d : CTD_UDINT; tick, load : BOOL; END_VAR
d(CD := tick, LD := load, PV := 1);
END_PROGRAM
""")
    vm["Main.load"] = True
    vm.run(cycles=1)
    vm["Main.load"] = False
    _pulses(vm, 4)
    assert vm["Main.d.CV"] == 0 and vm["Main.d.Q"] is True


def test_ctu_udint_stops_at_its_maximum():
    vm = start_st("""
PROGRAM Main
VAR c : CTU_UDINT; tick : BOOL; END_VAR
c(CU := tick, PV := 1);
END_PROGRAM
""")
    vm.run(cycles=1)
    vm["Main.c.CV"] = 4294967295
    _pulses(vm, 2)
    assert vm["Main.c.CV"] == 4294967295


def test_pv_of_the_wrong_type_is_a_diagnostic():
    rc, err = check_text("""PROGRAM Main
VAR c : CTU_INT; big : DINT; END_VAR
c(CU := TRUE, PV := big);
END_PROGRAM
""")
    assert rc == 1
    assert "case.st:3:" in err and "DINT" in err and "error:" in err
