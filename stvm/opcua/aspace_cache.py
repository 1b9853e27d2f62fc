"""asyncua's standard address space from stvm's signed cache: fast starts, no code from a file
someone else wrote.

Building asyncua's ~6,000 standard nodes takes 2–3 s. asyncua can keep them in a `shelve` file
(`Server.init(shelf_file=…)`) and load each node lazily when it is first used, but a shelf is a
pickle database: whoever can write the file runs code in the server's process. So stvm never
opens a shelf file. Instead:

* **Build** (first start, or when the entry is missing, damaged, forged or from another asyncua or
  Python): asyncua fills its address space from its generated code as without a cache; then each
  node is pickled (exactly what asyncua's `make_aspace_shelf` stores: node id text → pickled
  `NodeData`) and all records go into ONE entry of `stvm.cache.SignedCache`, in the record format
  below, signed with the user's key (HMAC-SHA256).
* **Load**: `SignedCache.get` reads the entry once and verifies its tag over the bytes it read;
  only then are the records split (no pickle: length-prefixed fields) into an in-memory mapping,
  and asyncua's address space gets a lazy node dict over `shelve.Shelf(that mapping)`. A node is
  unpickled on first use, from the verified bytes in memory: nothing is read from disk after the
  check, so there is no window between checking and using.
* An entry that does not verify, or whose records do not parse, is treated as missing and rebuilt
  (the start goes on). A cache folder other users can write, or that another user owns, is
  refused (`stvm.folders.folder_problem`, through `SignedCache`): the server starts without a
  cache and writes none. New cache folders are created 0700, entries 0600.

Record format (all integers unsigned 32-bit big-endian): the 16-byte `MAGIC`, the record count,
then per record the key's length, the key (UTF-8 node id text such as `i=84`), the value's length
and the value (one pickled node).
"""

from __future__ import annotations

import asyncio
import collections.abc
import pickle
import shelve
import struct
import sys
from typing import Any, Iterator

from asyncua import Server, ua
from asyncua.server.address_space import NodeData

from stvm.cache import SignedCache
from stvm.folders import default_folder

MAGIC = b"stvm-aspace-v1\n\0"
_U32 = struct.Struct(">I")
# a node that every standard address space has: checked (unpickled) when an entry is loaded
_PROBE = ua.NodeId(ua.ObjectIds.RootFolder)


def entry_name() -> str:
    """The cache entry's name: pickles are only valid for the asyncua and Python that made them."""
    import asyncua
    return f"opcua-aspace-asyncua{asyncua.__version__}-py{sys.version_info[0]}{sys.version_info[1]}.bin"


def encode(records: dict[str, bytes]) -> bytes:
    """`records` (node id text → pickled node) in the record format."""
    parts = [MAGIC, _U32.pack(len(records))]
    for key, value in records.items():
        raw = key.encode("utf-8")
        parts += [_U32.pack(len(raw)), raw, _U32.pack(len(value)), value]
    return b"".join(parts)


def decode(payload: bytes) -> dict[bytes, bytes] | None:
    """The records of `payload` (keys as UTF-8 bytes, as `shelve.Shelf` looks them up), or None if
    it is not in the record format. Splits bytes only; unpickles nothing."""
    if not payload.startswith(MAGIC) or len(payload) < len(MAGIC) + 4:
        return None
    view = memoryview(payload)
    (count,), pos = _U32.unpack_from(view, len(MAGIC)), len(MAGIC) + 4
    end = len(payload)
    records: dict[bytes, bytes] = {}
    for _ in range(count):
        fields = []
        for _field in range(2):
            if pos + 4 > end:
                return None
            (size,) = _U32.unpack_from(view, pos)
            pos += 4
            if pos + size > end:
                return None
            fields.append(bytes(view[pos:pos + size]))
            pos += size
        records[fields[0]] = fields[1]
    return records if pos == end and len(records) == count else None


def pickled_nodes(nodes) -> dict[str, bytes]:
    """asyncua's freshly built standard nodes as records (what `make_aspace_shelf` would store)."""
    return {nodeid.to_string(): pickle.dumps(data, pickle.HIGHEST_PROTOCOL) for nodeid, data in nodes.items()}


class VerifiedNodes(collections.abc.MutableMapping):
    """asyncua's address-space node dict over a `shelve.Shelf` of verified in-memory records: a
    standard node is unpickled when first used and then kept; nodes added later (stvm's own, and
    any change asyncua makes) live in the dict only. Like asyncua's own lazy dict for shelves,
    iteration and len() cover the nodes used so far."""

    def __init__(self, source: shelve.Shelf) -> None:
        self.source = source
        self.cache: dict[ua.NodeId, NodeData] = {}

    def __getitem__(self, key: ua.NodeId) -> NodeData:
        try:
            return self.cache[key]
        except KeyError:
            if not isinstance(key, ua.NodeId):
                raise
            node = self.cache[key] = self.source[key.to_string()]
            return node

    def __setitem__(self, key: ua.NodeId, value: NodeData) -> None:
        self.cache[key] = value

    def __contains__(self, key: object) -> bool:
        return key in self.cache or (isinstance(key, ua.NodeId) and key.to_string() in self.source)

    def __delitem__(self, key: ua.NodeId) -> None:
        del self.cache[key]

    def __iter__(self) -> Iterator[ua.NodeId]:
        return iter(self.cache.keys())

    def __len__(self) -> int:
        return len(self.cache)


def _nodes_from(payload: bytes | None) -> VerifiedNodes | None:
    """The lazy node dict over a verified payload; None if the payload is unusable."""
    if payload is None:
        return None
    records = decode(payload)
    if not records:
        return None
    nodes = VerifiedNodes(shelve.Shelf(records, protocol=pickle.HIGHEST_PROTOCOL))   # type: ignore[arg-type]
    try:
        probe = nodes[_PROBE]   # our own bytes (the tag verified), built by this asyncua and Python
    except Exception:   # noqa: BLE001 - an entry this asyncua cannot read: rebuild it
        return None
    return nodes if isinstance(probe, NodeData) else None


async def init_server(server: Server, cache: SignedCache | None = None) -> str:
    """`server.init()` with the standard address space from the signed cache when it verifies,
    else built (and stored when the cache folder is safe). Returns how: "cache", "built and
    cached" or "built" (no usable cache), for tests and the log."""
    cache = cache if cache is not None else SignedCache(default_folder())
    iserver = server.iserver
    name = entry_name()
    how = ["built"]

    async def load_standard_address_space(shelf_file: Any = None) -> None:
        # replaces InternalServer.load_standard_address_space, which Server.init() calls first:
        # asyncua's own shelf code (shelve.open on a path) is never reached
        nodes = _nodes_from(await asyncio.to_thread(cache.get, name))
        if nodes is not None:
            iserver.aspace._nodes = nodes
            how[0] = "cache"
            return
        from asyncua.server.standard_address_space import standard_address_space   # lazy: only when building
        await asyncio.to_thread(standard_address_space.fill_address_space, iserver.node_mgt_service)
        if cache.usable:   # known after get(): a refused folder gets nothing written
            # pickled now, before Server.init() changes any node: the same nodes asyncua's shelf holds
            payload = await asyncio.to_thread(lambda: encode(pickled_nodes(iserver.aspace._nodes)))
            await asyncio.to_thread(cache.put, name, payload)
            cache.prune("opcua-aspace-*.bin", keep=2)
            how[0] = "built and cached"

    iserver.load_standard_address_space = load_standard_address_space
    await server.init()
    return how[0]
