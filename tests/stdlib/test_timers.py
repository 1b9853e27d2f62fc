"""TON/TOF/TP scan by scan on the virtual clock (sysmac.md 7): exact Q and ET per call."""

from __future__ import annotations

import pytest

from stdlib_helpers import MS, FBRunner, make_ctx


def run_timer(name: str, rows, **settings):
    """rows: (time_ms, IN, PT_ms, expected Q, expected ET_ms); one call per row."""
    ctx = make_ctx(**settings)
    timer = FBRunner(name, ctx, IN=False, PT=0, Q=False, ET=0)
    for time_ms, signal, preset_ms, q, et_ms in rows:
        ctx.now_ns = time_ms * MS
        timer.step(IN=signal, PT=preset_ms * MS)
        assert (timer.Q, timer.ET) == (q, et_ms * MS), f"at {time_ms} ms"


def test_ton_delays_then_latches_until_in_falls():
    run_timer("TON", [
        (0, True, 30, False, 0),
        (10, True, 30, False, 10),
        (20, True, 30, False, 20),
        (30, True, 30, True, 30),
        (40, True, 30, True, 30),
        (50, True, 5, True, 30),      # latched: a later PT alters nothing
        (60, False, 30, False, 0),
        (70, True, 30, False, 0),     # restarts from now
        (100, True, 30, True, 30),
    ])


def test_ton_in_false_from_the_start():
    run_timer("TON", [(0, False, 30, False, 0), (10, False, 30, False, 0)])


def test_ton_overshoot_gives_et_pt():
    run_timer("TON", [(0, True, 25, False, 0), (20, True, 25, False, 20), (40, True, 25, True, 25)])


def test_ton_pt_raised_during_timing_is_used():
    run_timer("TON", [(0, True, 30, False, 0), (20, True, 50, False, 20), (40, True, 50, False, 40),
                      (50, True, 50, True, 50)])


def test_ton_pt_lowered_below_et_fires_at_once():
    run_timer("TON", [(0, True, 100, False, 0), (40, True, 10, True, 10), (50, True, 100, True, 10)])


def test_ton_pt_lowered_below_et_keep_timing():
    run_timer("TON", [(0, True, 100, False, 0), (40, True, 10, False, 40), (90, True, 10, False, 90),
                      (100, True, 10, True, 100)], ton_pt_below_et="keep_timing")


@pytest.mark.parametrize(("setting", "et_ms"), [("zero", 0), ("pt", -5)])
def test_ton_nonpositive_pt(setting, et_ms):
    run_timer("TON", [(0, False, -5, False, 0), (10, True, -5, True, et_ms)],
              ton_nonpositive_pt_et=setting)


def test_ton_zero_pt_fires_on_first_call():
    run_timer("TON", [(0, True, 0, True, 0)])


def test_ton_not_called_freezes_and_et_jumps():
    # sysmac.md 8 #14: skipped scans freeze the instance; ET jumps at the next call
    run_timer("TON", [(0, True, 1000, False, 0), (10, True, 1000, False, 10),
                      (700, True, 1000, False, 700), (1500, True, 1000, True, 1000)])


def test_ton_call_time_clock_uses_the_vm_hook():
    ctx = make_ctx(timer_clock="call_time")
    ctx.call_time_ns = lambda: ctx.now_ns + 3 * MS
    timer = FBRunner("TON", ctx, IN=False, PT=0, Q=False, ET=0)
    timer.step(IN=True, PT=10 * MS)
    ctx.now_ns = 5 * MS
    timer.step()
    assert timer.ET == 5 * MS  # both calls read the hook: (5 + 3) - (0 + 3)


def test_ton_call_time_without_hook_reads_scan_start():
    run_timer("TON", [(0, True, 30, False, 0), (10, True, 30, False, 10)], timer_clock="call_time")


def test_tof_holds_q_for_pt_after_in_falls():
    run_timer("TOF", [
        (0, False, 30, False, 0),     # never on: Q FALSE
        (10, True, 30, True, 0),
        (20, False, 30, True, 0),     # falling edge: timing starts now
        (30, False, 30, True, 10),
        (40, False, 30, True, 20),
        (50, False, 30, False, 30),
        (60, False, 30, False, 30),   # held until IN is TRUE
        (70, True, 30, True, 0),
    ])


def test_tof_in_back_true_during_timing_stops_it():
    run_timer("TOF", [(0, True, 30, True, 0), (10, False, 30, True, 0), (20, True, 30, True, 0),
                      (30, False, 30, True, 0), (50, False, 30, True, 20), (60, False, 30, False, 30)])


def test_tof_zero_pt_drops_at_the_fall():
    run_timer("TOF", [(0, True, 0, True, 0), (10, False, 0, False, 0)])


def test_tp_pulse_while_in_held():
    run_timer("TP", [
        (0, True, 30, True, 0),
        (10, True, 30, True, 10),
        (20, True, 30, True, 20),
        (30, True, 30, False, 30),    # pulse over, IN still TRUE: ET stays PT
        (40, True, 30, False, 30),
        (50, False, 30, False, 0),
        (60, True, 30, True, 0),      # a new rising edge: a new pulse
    ])


def test_tp_is_not_retriggerable_and_ends_with_in_false():
    run_timer("TP", [
        (0, True, 30, True, 0),
        (10, False, 30, True, 10),    # IN falls: the pulse runs on
        (20, True, 30, True, 20),     # rising edge during the pulse: ignored
        (30, False, 30, False, 0),    # ends with IN FALSE: ET 0 at once
        (40, False, 30, False, 0),
    ])


def test_tp_first_call_false_then_rise():
    run_timer("TP", [(0, False, 30, False, 0), (10, True, 30, True, 0), (40, True, 30, False, 30)])
