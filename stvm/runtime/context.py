"""What a running VM offers native POUs: the clock, the settings, the socket transport, warnings."""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from typing import Any, Callable

from stvm.settings import DEFAULT_SETTINGS, SysmacSettings


@dataclass
class RunContext:
    """Per-run state visible to native code (`ctx` in every native call).

    `now_ns` is the virtual time at the start of the current scan (the VM clock, never the wall
    clock); `start_dt_ns` is the DATE_AND_TIME that virtual time 0 stands for (GetTime returns
    `start_dt_ns + now_ns`). `transport` is the socket transport the Skt* FBs use (real TCP by
    default; an in-process emulator link in lockstep runs).
    """

    settings: SysmacSettings = DEFAULT_SETTINGS
    now_ns: int = 0
    scan: int = 0
    task: str = ""
    start_dt_ns: int = 0
    realtime: bool = False
    transport: Any = None
    # the VM between whose scans a real socket service runs (set by `stvm run`: reads before each
    # scan, sends after it, as the controller's system service); None: every socket FB call polls
    socket_service_vm: Any = None
    warn_sink: Callable[[str], None] | None = None
    _warned: set = field(default_factory=set)

    def warn(self, message: str, once_key: object | None = None) -> None:
        """Report a runtime warning on stderr (once per `once_key` when given)."""
        if once_key is not None:
            if once_key in self._warned:
                return
            self._warned.add(once_key)
        if self.warn_sink is not None:
            self.warn_sink(message)
        else:
            print(f"warning: {message}", file=sys.stderr)

    def warn_at(self, span: Any, message: str, once_key: object | None = None) -> None:
        """Report a runtime warning at an ST location as `FILE:LINE:COL: warning: message`,
        the diagnostics' format (once per `once_key` when given)."""
        if once_key is not None:
            if once_key in self._warned:
                return
            self._warned.add(once_key)
        text = f"{span.file}:{span.line}:{span.column}: warning: {message}"
        if self.warn_sink is not None:
            self.warn_sink(text)
        else:
            print(text, file=sys.stderr)
