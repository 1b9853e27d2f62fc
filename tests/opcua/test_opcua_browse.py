"""Issue 32 item 12 (browse): a Browse honours RequestedMaxReferencesPerNode with a continuation
point, BrowseNext continues and releases it, points are bounded per session (asyncua's client)."""

from __future__ import annotations

from asyncua import Client, ua

from opcua_helpers import run_async
from stvm.opcua.browse import MAX_CONTINUATION_POINTS


def _browse(nodeid, per_node: int) -> ua.BrowseParameters:
    desc = ua.BrowseDescription(NodeId=nodeid, BrowseDirection=ua.BrowseDirection.Forward,
                                ReferenceTypeId=ua.NodeId(ua.ObjectIds.HierarchicalReferences),
                                IncludeSubtypes=True, ResultMask=ua.BrowseResultMask.All)
    return ua.BrowseParameters(NodesToBrowse=[desc], RequestedMaxReferencesPerNode=per_node)


def test_browse_pages_with_continuation_points_and_browse_next(running):
    async def body():
        async with Client(running.url) as client:
            ns = await client.get_namespace_index(running.ns_uri)
            folder = ua.NodeId("@Globals", ns)
            everything = [ref.NodeId for ref in (await client.uaclient.browse(_browse(folder, 0)))[0].References]
            assert len(everything) > 12
            first = (await client.uaclient.browse(_browse(folder, 5)))[0]
            assert first.StatusCode.is_good() and len(first.References) == 5 and first.ContinuationPoint
            seen = [ref.NodeId for ref in first.References]
            point = first.ContinuationPoint
            while point:
                result = (await client.uaclient.browse_next(
                    ua.BrowseNextParameters(ReleaseContinuationPoints=False, ContinuationPoints=[point])))[0]
                assert result.StatusCode.is_good() and len(result.References) <= 5
                seen += [ref.NodeId for ref in result.References]
                point = result.ContinuationPoint
            assert seen == everything
            # a finished point is gone
            gone = (await client.uaclient.browse_next(
                ua.BrowseNextParameters(ReleaseContinuationPoints=False, ContinuationPoints=[first.ContinuationPoint])))
            assert gone[0].StatusCode.value == ua.StatusCodes.BadContinuationPointInvalid
            # released: Good, no references, then invalid
            again = (await client.uaclient.browse(_browse(folder, 3)))[0]
            released = await client.uaclient.browse_next(
                ua.BrowseNextParameters(ReleaseContinuationPoints=True, ContinuationPoints=[again.ContinuationPoint]))
            assert released[0].StatusCode.is_good() and released[0].References == []
            after = await client.uaclient.browse_next(
                ua.BrowseNextParameters(ReleaseContinuationPoints=False, ContinuationPoints=[again.ContinuationPoint]))
            assert after[0].StatusCode.value == ua.StatusCodes.BadContinuationPointInvalid
            # bounded: one more point than the session may hold is BadNoContinuationPoints
            for _ in range(MAX_CONTINUATION_POINTS):
                assert (await client.uaclient.browse(_browse(folder, 1)))[0].ContinuationPoint
            over = (await client.uaclient.browse(_browse(folder, 1)))[0]
            assert over.StatusCode.value == ua.StatusCodes.BadNoContinuationPoints
            # asyncua's own walk (Browse with 0, then BrowseNext) still sees every child
            children = await client.get_node(folder).get_children()
            assert [c.nodeid for c in children] == everything
            # the server keeps serving
            assert await client.get_node(ua.NodeId("MoveAbs_Param.Speed", ns)).read_value() is not None
    run_async(body())
