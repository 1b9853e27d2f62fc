"""Keeping a real-time scan loop on its deadlines (`stvm run --realtime`).

What the OS offers, each measured (README, Benchmarks; `python bench/bench_realtime.py`):

* Absolute deadlines: every release time is `start + n * period` on the monotonic clock, never
  "now + period", so lateness does not accumulate.
* Timer slack: Linux lets a sleeping thread wake up to 50 µs late by default (to batch
  wake-ups); the scan thread asks for 1 ns (`prctl(PR_SET_TIMERSLACK)`).
* A short spin: the thread sleeps until `SPIN_NS` before the deadline and busy-waits the rest,
  so the wake-up latency of the OS is hidden when it is below `SPIN_NS` (the spin costs up to
  `SPIN_NS` of CPU a period: 20 % of a core at 1 ms). At normal priority on a machine whose
  cores are all busy the spin makes overruns worse (the scheduler then treats the loop as
  CPU-bound and wakes it later); on a quiet one it is what brings the p99 under 100 µs
  (`SPIN_NS_NORMAL`, measured in bench/bench_realtime.py).
* The garbage collector off during the scan loop: the objects that exist when the loop starts
  are frozen (`gc.freeze()`, never scanned again) and the young generation is collected between
  scans, when at least `GC_IDLE_NS` remain before the next deadline (or when garbage has piled
  up to 16 thresholds), so a collection never delays a scan's start.
* Optionally a real-time scheduling class: `STVM_RT_PRIORITY=N` (1..99) puts the scan thread in
  SCHED_FIFO at priority N when the user may (root, CAP_SYS_NICE or an `rtprio` limit); the
  kernel's RT throttling still leaves 5 % of each second to other processes. Not the default:
  a real-time process that loops forever starves the other work of its core.
"""

from __future__ import annotations

import gc
import os
import sys
import threading
import time

# the knobs (module level, so bench/bench_realtime.py can measure each alone)
SPIN_NS = 200_000          # busy-wait this long before each deadline, in a real-time class
SPIN_NS_NORMAL = 200_000   # the same at normal priority (measured, 10 s each: at load 1 the spin
                           # took the p99 from 1,335 to 73 us and overruns from 0.51 to 0.14 %; at
                           # load 4.5 it made overruns worse, 2.3 -> 5.0 %: the target is an idle machine)
GC_IDLE_NS = 300_000       # collect between scans only with this much time left
MANAGE_GC = True           # False: the collector runs whenever it likes, inside scans too
TIMER_SLACK_NS = 1         # None: keep the OS default (50 µs on Linux)
_PR_SET_TIMERSLACK = 29

_GC_LOCK = threading.Lock()
_GC_HOLDERS: set[int] = set()     # the Pacers holding the collector
_GC_STATE: dict[str, bool] = {}


def _set_timer_slack(ns: int) -> bool:
    if not sys.platform.startswith("linux"):
        return False
    try:
        import ctypes   # lazy: start-up (only a real-time run sets the slack)
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(_PR_SET_TIMERSLACK, ctypes.c_ulong(ns), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _real_time_class() -> str:
    """SCHED_FIFO at STVM_RT_PRIORITY when asked for and allowed; the policy in force, as text."""
    wanted = os.environ.get("STVM_RT_PRIORITY", "").strip()
    if wanted and hasattr(os, "sched_setscheduler"):
        try:
            priority = int(wanted)
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
            return f"SCHED_FIFO {priority}"
        except (ValueError, OSError) as exc:
            print(f"stvm: warning: STVM_RT_PRIORITY={wanted}: real-time scheduling not available "
                  f"({getattr(exc, 'strerror', None) or exc}); running at normal priority", file=sys.stderr)
    return "SCHED_OTHER"


class Pacer:
    """Waits for each deadline of a real-time VM (see the module docstring)."""

    def __init__(self) -> None:
        self.manage_gc = MANAGE_GC
        self.timer_slack = TIMER_SLACK_NS is not None and _set_timer_slack(TIMER_SLACK_NS)
        self.policy = _real_time_class()
        self.spin_ns = SPIN_NS if self.policy != "SCHED_OTHER" else SPIN_NS_NORMAL
        # the statistics fold their ring with numpy every 4096 values: import it now, before the
        # first deadline, not inside the loop (an import under load stalled a run by 240 ms)
        import numpy  # noqa: F401  (lazy: start-up, real-time runs only)
        self.gc_managed = False
        self.gc_collections = 0     # collections run between scans

    # ---- the garbage collector during the scan loop
    def take_gc(self) -> None:
        """The collector off (the heap frozen) while this VM's loop runs. The collector is the
        process's: several real-time VMs at once (threads) share one hold, the last gives it back."""
        if self.gc_managed or not self.manage_gc:
            return
        with _GC_LOCK:
            if not _GC_HOLDERS:
                _GC_STATE["was_enabled"] = gc.isenabled()
                gc.collect()
                gc.freeze()
                gc.disable()
            _GC_HOLDERS.add(id(self))
        self.gc_managed = True

    def release_gc(self) -> None:
        if not self.gc_managed:
            return
        self.gc_managed = False
        with _GC_LOCK:
            _GC_HOLDERS.discard(id(self))
            if not _GC_HOLDERS:
                gc.unfreeze()
                if _GC_STATE.get("was_enabled"):
                    gc.enable()

    def _collect_if_due(self, idle_ns: int) -> None:
        count0, count1, count2 = gc.get_count()
        threshold0, threshold1, threshold2 = gc.get_threshold()
        if threshold0 <= 0 or count0 < threshold0:
            return
        if idle_ns < GC_IDLE_NS and count0 < 16 * threshold0:
            return          # no time before this deadline: at a later one
        # the generation the collector itself would choose
        generation = 2 if count2 >= threshold2 > 0 else 1 if count1 >= threshold1 > 0 else 0
        gc.collect(generation)
        self.gc_collections += 1

    # ---- waiting
    def wait_until(self, deadline_ns: int) -> int:
        """Sleep, then spin, until `deadline_ns` (perf_counter_ns); the time it returns at."""
        clock = time.perf_counter_ns
        if self.gc_managed:
            self._collect_if_due(deadline_ns - clock())
        remaining = deadline_ns - clock()
        if remaining > self.spin_ns:
            time.sleep((remaining - self.spin_ns) / 1e9)
        now = clock()
        while now < deadline_ns:
            now = clock()
        return now
