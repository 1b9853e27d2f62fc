"""A TM (Techman/Omron) robot speaking the Listen Node protocol, for tests without a robot.

Public API::

    import emulator
    server = emulator.start_server(host="127.0.0.1", port=0)   # background thread
    print(server.port)
    server.stop()

    link = emulator.InProcessLink(latency_ns=1_000_000)        # deterministic, virtual clock
    client = link.endpoint(); client.connect(); link.step(2_000_000)

See ``docs/emulator.md`` and the docstrings of :mod:`emulator.transport` and
:mod:`emulator.settings`.
"""

from .faults import NO_FAULTS, FaultPlan, parse_fault, parse_faults
from .framing import Cperr, Frame, FrameError, ListenNodeFramer, encode
from .robot import NodeState, Robot
from .settings import DEFAULT_SETTINGS, EmulatorSettings
from .transport import ClientEndpoint, InProcessLink, TcpServer, start_server

__all__ = [
    "ClientEndpoint", "Cperr", "DEFAULT_SETTINGS", "EmulatorSettings", "FaultPlan", "Frame", "FrameError",
    "InProcessLink", "ListenNodeFramer", "NO_FAULTS", "NodeState", "Robot", "TcpServer", "encode",
    "parse_fault", "parse_faults", "start_server",
]
