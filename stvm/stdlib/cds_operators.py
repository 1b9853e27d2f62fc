"""Natives of stvm/stdlib/cds_operators.st (`--dialect codesys` and `--dialect twincat`).

TIME(): CODESYS online help, "Functions" ("TIME() function: the time in milliseconds since the
system started; a 32-bit TIME, after an overflow it starts again at 0"). stvm has no system start
other than the run's: the value is the virtual clock at the start of the scan plus BOOT_MS, the
same boot offset as GETCPUCOUNTER (stvm/stdlib/tc2_system.py), so code that treats 0 as "never"
works from the first scan, and a run is deterministic.
"""

from __future__ import annotations

from stvm.stdlib.registry import native_function

BOOT_MS = 1000          # choice: as if the system started 1 s before the first scan
TIME32_MS = 1 << 32     # TIME() is 32 bits of milliseconds


@native_function("TIME")
def time_since_start(ctx) -> int:
    ms = (ctx.now_ns // 1_000_000 + BOOT_MS) % TIME32_MS
    return ms * 1_000_000    # stvm keeps a TIME in nanoseconds
