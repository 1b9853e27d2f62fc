"""Scan-time and start-jitter statistics in bounded memory (a run may last a whole shift).

`TimingStats` keeps exact count, sum, min and max, the last `window` values exactly (a ring
buffer, what the demo's "last 1000 scans" row shows) and a log-linear histogram of everything
older, from which quantiles are read. Memory is fixed at construction: about 30 KiB of histogram
plus 8 bytes per window slot, whatever the number of scans.

The hot path (`add`, once per scan) only stores into a preallocated array; the ring is folded
into the histogram with numpy once every `window` values.

Quantile precision: exact while no more than `window` values were recorded (the same figures as
sorting them all); after that, a value's bucket is exact below 128 ns and within 1/64 (1.6 %)
above, and a quantile is reported as the midpoint of its bucket, clamped to [min, max].
"""

from __future__ import annotations

from array import array
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

# numpy is imported on first use (the first fold or summary), not with the VM: `stvm run` of a
# short program must not pay numpy's import time.

# Choice: a hand-written HDR-style histogram rather than a sketch library. `add` runs once per
# scan inside the scan loop (a toggle program scans in under 1 µs), where a library's
# per-value Python call would cost more than the scan; folding a whole ring at once with numpy
# keeps the per-scan cost to one array store.
_SUB_BITS = 6
_SUB = 1 << _SUB_BITS                 # buckets per power of two (relative error < 1/64)
_BUCKETS = (64 - _SUB_BITS + 1) * _SUB  # enough for any int64


def _bucket_indices(values: "np.ndarray") -> "np.ndarray":
    """Histogram bucket of each (non-negative int64) value."""
    import numpy as np
    v = np.maximum(values, 0)
    bits = np.frexp(v.astype(np.float64))[1].astype(np.int64)   # bit_length (exact below 2**53)
    shift = np.maximum(bits - (_SUB_BITS + 1), 0)
    # values below 128 sit in buckets 0..127 exactly; above, (shift, top 7 bits) picks the
    # bucket: the top bits are 64..127, so a bucket spans 1/64 of its power of two
    return np.where(shift == 0, v, shift * _SUB + (v >> shift)).astype(np.int64)


def _bucket_value(index: int) -> float:
    """The midpoint of a bucket (the value a quantile in it is reported as)."""
    if index < 2 * _SUB:
        return float(index)
    shift = index // _SUB - 1
    top = index - shift * _SUB          # 64..127
    return (top + 0.5) * (1 << shift)


class TimingStats:
    """Durations in integer nanoseconds, in bounded memory (see the module docstring)."""

    __slots__ = ("window", "_ring", "_pos", "_histogram", "_count", "_total", "_min", "_max")

    def __init__(self, window: int = 4096) -> None:
        if window <= 0:
            raise ValueError("window must be positive")
        self.window = window
        self._ring = array("q", bytes(8 * window))
        self._pos = 0            # next slot of the ring = ring values not yet in the histogram
        self._histogram: "np.ndarray | None" = None
        # count, sum, min and max of the values folded so far (the ring's pending part is added
        # when read: `add`, once per scan, only stores)
        self._count = 0
        self._total = 0
        self._min: int | None = None
        self._max: int | None = None

    def add(self, value_ns: int) -> None:
        pos = self._pos
        self._ring[pos] = value_ns
        pos += 1
        if pos == self.window:
            self._fold()
            pos = 0
        self._pos = pos

    @property
    def _pending(self) -> int:
        return self._pos

    @property
    def count(self) -> int:
        return self._count + self._pos

    @property
    def total(self) -> int:
        return self._total + sum(self._ring[:self._pos])

    @property
    def minimum(self) -> int | None:
        if not self._pos:
            return self._min
        low = min(self._ring[:self._pos])
        return low if self._min is None or low < self._min else self._min

    @property
    def maximum(self) -> int | None:
        if not self._pos:
            return self._max
        high = max(self._ring[:self._pos])
        return high if self._max is None or high > self._max else self._max

    def _fold(self) -> None:
        """The whole ring (all pending) into the histogram and the folded aggregates."""
        import numpy as np
        ring = self._ring
        self._count += self.window
        self._total += sum(ring)
        low, high = min(ring), max(ring)
        self._min = low if self._min is None or low < self._min else self._min
        self._max = high if self._max is None or high > self._max else self._max
        histogram = self._histogram
        if histogram is None:
            histogram = self._histogram = np.zeros(_BUCKETS, dtype=np.int64)
        histogram += np.bincount(_bucket_indices(np.frombuffer(self._ring, dtype=np.int64)),
                                 minlength=_BUCKETS)

    def __len__(self) -> int:
        return self.count

    def recent(self, n: int | None = None) -> "np.ndarray":
        """The last `n` values (at most `window`), oldest first, as int64."""
        import numpy as np
        held = min(self.count, self.window)
        n = held if n is None else max(0, min(n, held))
        ring = np.frombuffer(self._ring, dtype=np.int64)
        end = self._pos
        if n <= end:
            return ring[end - n:end].copy()
        return np.concatenate([ring[self.window - (n - end):], ring[:end]])

    @property
    def mean_ns(self) -> float:
        return self.total / self.count if self.count else 0.0

    def quantile_ns(self, q: float) -> float:
        """The `q` quantile (0..1); exact while count <= window, else a bucket midpoint."""
        import numpy as np
        if not self.count:
            raise ValueError("no values recorded")
        if self._histogram is None:
            return float(np.percentile(self.recent(), q * 100.0))
        histogram = self._histogram
        if self._pending:
            histogram = histogram + np.bincount(_bucket_indices(self.recent(self._pending)),
                                                minlength=_BUCKETS)
        rank = q * (self.count - 1)
        index = int(np.searchsorted(np.cumsum(histogram), rank, side="right"))
        value = _bucket_value(index)
        return float(min(max(value, self.minimum), self.maximum))

    def summary_us(self) -> tuple[float, float, float, float] | None:
        """(mean, p50, p99, max) in µs; None if nothing was recorded."""
        if not self.count:
            return None
        return (self.mean_ns / 1000.0, self.quantile_ns(0.50) / 1000.0, self.quantile_ns(0.99) / 1000.0,
                self.maximum / 1000.0)

    def nbytes(self) -> int:
        """Memory held by the values (fixed after the first fold)."""
        return len(self._ring) * 8 + (0 if self._histogram is None else self._histogram.nbytes)
