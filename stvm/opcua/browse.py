"""Browse with continuation points, and BrowseNext (OPC UA Part 4 §5.9.2, §5.9.3, §7.6).

asyncua 2.1 answers Browse with every reference of a node whatever the client's
`RequestedMaxReferencesPerNode`, and has no BrowseNext at all (its processor answers
BadServiceUnsupported). Here:

* Browse returns at most `RequestedMaxReferencesPerNode` references per node (0: no limit, the
  server's own `MAX_REFERENCES_PER_NODE` still applies); the rest waits behind a continuation
  point (16 random bytes) that belongs to the session.
* BrowseNext continues (same count per node as the Browse that made the point) or releases
  (`ReleaseContinuationPoints`); an unknown or released point is BadContinuationPointInvalid.
* A session holds at most `MAX_CONTINUATION_POINTS` (advertised as the server capability
  MaxBrowseContinuationPoints); a Browse that would need one more gets BadNoContinuationPoints for
  that node (Part 4 §5.9.2.4), never an unbounded store.
"""

from __future__ import annotations

import secrets
import time
from collections import OrderedDict
from dataclasses import dataclass

from asyncua import ua
from asyncua.common.utils import ServiceError
from asyncua.server.uaprocessor import UaProcessor
from asyncua.ua.ua_binary import struct_from_binary

MAX_CONTINUATION_POINTS = 16
MAX_REFERENCES_PER_NODE = 1000   # per Browse answer when the client asks for no limit (0)


@dataclass
class _Pending:
    references: list
    per_node: int


class ContinuationPoints:
    """One session's continuation points (the server loop only)."""

    def __init__(self, capacity: int = MAX_CONTINUATION_POINTS) -> None:
        self.capacity = capacity
        self._points: OrderedDict[bytes, _Pending] = OrderedDict()

    def __len__(self) -> int:
        return len(self._points)

    def page(self, result: ua.BrowseResult, requested: int) -> ua.BrowseResult:
        """Cut `result` to the requested count; keep the rest behind a continuation point."""
        per_node = requested if 0 < requested <= MAX_REFERENCES_PER_NODE else MAX_REFERENCES_PER_NODE
        refs = result.References
        if len(refs) <= per_node:
            return result
        if len(self._points) >= self.capacity:
            return ua.BrowseResult(StatusCode=ua.StatusCode(ua.StatusCodes.BadNoContinuationPoints))
        point = secrets.token_bytes(16)
        self._points[point] = _Pending(refs[per_node:], per_node)
        result.References = refs[:per_node]
        result.ContinuationPoint = point
        return result

    def next(self, params: ua.BrowseNextParameters) -> list[ua.BrowseResult]:
        results = []
        for point in params.ContinuationPoints:
            pending = self._points.pop(point, None) if point else None
            if pending is None:
                results.append(ua.BrowseResult(StatusCode=ua.StatusCode(ua.StatusCodes.BadContinuationPointInvalid)))
                continue
            if params.ReleaseContinuationPoints:
                results.append(ua.BrowseResult())   # released: Good, no references
                continue
            now, rest = pending.references[:pending.per_node], pending.references[pending.per_node:]
            result = ua.BrowseResult(References=now)
            if rest:
                self._points[point] = _Pending(rest, pending.per_node)
                result.ContinuationPoint = point
            results.append(result)
        return results


class BrowsingProcessor(UaProcessor):
    """asyncua's request processor with BrowseNext (the only request it lacks that clients send
    after a Browse with continuation points)."""

    async def _process_message(self, typeid, requesthdr, seqhdr, body):
        if typeid != ua.NodeId(ua.ObjectIds.BrowseNextRequest_Encoding_DefaultBinary):
            return await super()._process_message(typeid, requesthdr, seqhdr, body)
        if self.session is None or not self.session.is_activated():
            raise ua.uaerrors.BadSessionNotActivated
        self.session_last_activity = time.monotonic()
        self.session.touch()
        params = struct_from_binary(ua.BrowseNextParameters, body)
        browse_next = getattr(self.session, "browse_next_pages", None)
        if browse_next is None:
            raise ServiceError(ua.StatusCodes.BadServiceUnsupported)
        response = ua.BrowseNextResponse()
        response.Parameters.Results = browse_next(params)
        self.send_response(requesthdr.RequestHandle, seqhdr, response)
        return True
