"""IEC timers TON, TOF, TP on the VM clock (sysmac.md 7), and LTON, LTOF, LTP (ed. 3, on LTIME).

Native because they read the clock: "now" is `ctx.now_ns`, the virtual time at the start of the
scan (`timer_clock = scan_start`), never the wall clock. A timer updates only when its instance
is called (CONFIRMED for TON): skipped scans freeze it, and ET jumps at the next call.

Pins: IN BOOL, PT TIME → Q BOOL, ET TIME (Omron spells IN as `In`; names are case-insensitive).
The L forms take PT and give ET as LTIME; TIME and LTIME are both int nanoseconds, so each is the
same class as its TIME form, registered under a second name.
"""

from __future__ import annotations

from stvm.lower.bind import st_names
from stvm.stdlib.registry import native_fb
from stvm.settings import TimerClock, TonNonpositivePtEt, TonPtBelowEt

# a module constant: an Enum member read through its class costs a descriptor call, and TON
# compares with it at every call while it times (the thesis times with two TONs every scan)
_CALL_TIME = TimerClock.CALL_TIME


def timer_now(ctx) -> int:
    """The time a timer sees (sysmac.md 7, `timer_clock`).

    `call_time` needs a clock read at the call; the VM may offer it as `ctx.call_time_ns()`.
    Choice: without that hook (virtual time has no finer clock than the scan) both settings read
    the scan start.
    """
    if ctx.settings.timer_clock is _CALL_TIME:
        call_time = getattr(ctx, "call_time_ns", None)
        if callable(call_time):
            return call_time()
    return ctx.now_ns


class _PresetTracker:
    """The preset a running timer compares against (sysmac.md 7, `ton_pt_below_et`).

    A PT changed during timing is used when it is ≥ ET. A PT changed to below the elapsed time
    ends the timing at once (`q_true`: Q as if reached, ET := PT), or, with `keep_timing`, is
    ignored and the timer keeps running against the PT it had.
    Choice: "changed" means different from the PT of the previous call, so a PT that ET simply
    grew past is reached normally.
    """

    __slots__ = ("effective", "last_seen")

    def __init__(self) -> None:
        self.effective = 0
        self.last_seen = 0

    def start(self, preset: int) -> None:
        self.effective = self.last_seen = preset

    def update(self, ctx, preset: int, elapsed: int) -> int:
        if preset != self.last_seen:
            if preset >= elapsed or ctx.settings.ton_pt_below_et is TonPtBelowEt.Q_TRUE:
                self.effective = preset
            self.last_seen = preset
        return self.effective


def _elapsed_at_end(ctx, preset: int) -> int:
    """ET when a timer ends: PT; for PT ≤ 0, 0 or PT (sysmac.md 7, `ton_nonpositive_pt_et`)."""
    if preset <= 0 and ctx.settings.ton_nonpositive_pt_et is TonNonpositivePtEt.ZERO:
        return 0
    return preset


@native_fb("LTON")
@native_fb("TON")
@st_names("IN", "PT", "Q", "ET")
class OnDelayTimer:
    """TON: Q rises PT after IN rose; IN FALSE resets Q and ET at once (sysmac.md 7, CONFIRMED)."""

    def __init__(self) -> None:
        self.timing = False
        self.reached = False
        self.start_ns = 0
        self.preset = _PresetTracker()

    def call(self, inst, ctx) -> None:
        if not inst.IN:
            self.timing = self.reached = False
            inst.Q = False
            inst.ET = 0
            return
        if self.reached:
            return  # latched: later PT changes alter nothing
        # `timer_now` and `_PresetTracker.update` without their calls in the usual case (scan
        # start clock, PT as at the previous call): TON times every scan
        now = ctx.now_ns if ctx.settings.timer_clock is not _CALL_TIME else timer_now(ctx)
        tracker = self.preset
        if not self.timing:
            self.timing = True
            self.start_ns = now
            tracker.start(inst.PT)
        elapsed = now - self.start_ns
        pt = inst.PT
        preset = tracker.effective if pt == tracker.last_seen else tracker.update(ctx, pt, elapsed)
        if elapsed >= preset:
            self.timing, self.reached = False, True
            inst.Q = True
            inst.ET = _elapsed_at_end(ctx, preset)
        else:
            inst.Q = False
            inst.ET = elapsed


@native_fb("LTOF")
@native_fb("TOF")
@st_names("IN", "PT", "Q", "ET")
class OffDelayTimer:
    """TOF: Q follows IN up at once and falls PT after IN fell (sysmac.md 7)."""

    def __init__(self) -> None:
        self.previous_in = False
        self.timing = False
        self.start_ns = 0
        self.preset = _PresetTracker()

    def call(self, inst, ctx) -> None:
        signal = bool(inst.IN)
        falling = self.previous_in and not signal
        self.previous_in = signal
        if signal:
            self.timing = False
            inst.Q = True
            inst.ET = 0
            return
        now = timer_now(ctx)
        if falling:
            self.timing = True
            self.start_ns = now
            self.preset.start(inst.PT)
        if not self.timing:
            return  # Q FALSE, ET held (0 before IN was ever TRUE, PT after a completed delay)
        elapsed = now - self.start_ns
        preset = self.preset.update(ctx, inst.PT, elapsed)
        if elapsed >= preset:
            self.timing = False
            inst.Q = False
            inst.ET = _elapsed_at_end(ctx, preset)
        else:
            inst.Q = True
            inst.ET = elapsed


@native_fb("LTP")
@native_fb("TP")
@st_names("IN", "PT", "Q", "ET")
class PulseTimer:
    """TP: a rising IN with no pulse running gives Q TRUE for PT; not retriggerable; after the
    pulse ET stays PT while IN is TRUE and returns to 0 once IN is FALSE (sysmac.md 7)."""

    def __init__(self) -> None:
        self.previous_in = False
        self.pulsing = False
        self.ended = False  # the pulse is over but IN has not gone FALSE yet
        self.start_ns = 0
        self.preset = _PresetTracker()

    def call(self, inst, ctx) -> None:
        signal = bool(inst.IN)
        rising = signal and not self.previous_in
        self.previous_in = signal
        now = timer_now(ctx)
        if rising and not self.pulsing and not self.ended:
            self.pulsing = True
            self.start_ns = now
            self.preset.start(inst.PT)
        if self.pulsing:
            elapsed = now - self.start_ns
            preset = self.preset.update(ctx, inst.PT, elapsed)
            if elapsed < preset:
                inst.Q = True
                inst.ET = elapsed
                return
            self.pulsing = False
            self.ended = True
            inst.Q = False
            inst.ET = _elapsed_at_end(ctx, preset)
        if self.ended and not signal:
            # Choice: a pulse that ends while IN is already FALSE shows ET 0 in that same call
            self.ended = False
            inst.ET = 0
