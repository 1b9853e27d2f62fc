"""Beckhoff Tc2_Utilities natives (declarations in tc2_utilities.st, `--dialect twincat`).

FB_LocalSystemTime (Beckhoff Information System, TwinCAT 3 PLC Lib Tc2_Utilities,
"FB_LocalSystemTime", "TIMESTRUCT", "E_TimeZoneID"): on TwinCAT it reads the Windows local time
over ADS every dwCycle seconds and counts on between reads. stvm reads the clock Omron's GetTime
reads (stvm/stdlib/omron.py): the virtual date and time, the run's start DT plus the virtual clock,
so a run is deterministic; the host's local time in a real-time run.
Choices (stvm has no ADS round trip and no time-zone settings): bValid is TRUE from the first call
with bEnable (TwinCAT: after the first read completes, some cycles later); tzID is
eTimeZoneID_Unknown; with bEnable FALSE, bValid is FALSE and systemTime keeps its last value.
"""

from __future__ import annotations

import datetime as _dt

from stvm.lower.bind import st_names
from stvm.stdlib.registry import native_fb

_EPOCH = _dt.datetime(1970, 1, 1)
TZ_UNKNOWN = 0     # E_TimeZoneID.eTimeZoneID_Unknown


def local_now(ctx) -> _dt.datetime:
    if ctx.realtime:
        return _dt.datetime.now()
    return _EPOCH + _dt.timedelta(microseconds=(ctx.start_dt_ns + ctx.now_ns) // 1000)


@native_fb("FB_LocalSystemTime")
@st_names("bEnable", "bValid", "systemTime", "tzID", "wYear", "wMonth", "wDayOfWeek", "wDay", "wHour",
          "wMinute", "wSecond", "wMilliseconds")
class LocalSystemTime:
    def call(self, inst, ctx) -> None:
        if not inst.bEnable:
            inst.bValid = False
            return
        now = local_now(ctx)
        st = inst.systemTime
        st.wYear, st.wMonth, st.wDay = now.year, now.month, now.day
        st.wDayOfWeek = now.isoweekday() % 7       # TIMESTRUCT: 0 = Sunday
        st.wHour, st.wMinute, st.wSecond = now.hour, now.minute, now.second
        st.wMilliseconds = now.microsecond // 1000
        inst.tzID = TZ_UNKNOWN
        inst.bValid = True
