"""What the soak tests and benches share (tests/security/test_soak_*.py, bench/bench_soak_*.py):
the server's resident memory and open descriptors read from /proc, percentiles, and a pool of
hostile workers that each repeat one attack until a deadline.

A soak has three phases against one server process: quiet (the well-behaved client alone: the
baseline), hostile (the same client while the workers attack), and after (the workers gone).
Figures are compared with the baseline of the same run, never with fixed times."""

from __future__ import annotations

import os
import threading
import time
from dataclasses import dataclass, field
from typing import Callable


def rss_kb(pid: int) -> int:
    """Resident memory of process `pid` in KiB (Linux /proc)."""
    with open(f"/proc/{pid}/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise RuntimeError(f"no VmRSS for process {pid}")


def fd_count(pid: int) -> int:
    """Open descriptors of process `pid` (Linux /proc)."""
    return len(os.listdir(f"/proc/{pid}/fd"))


def pct(values: list[float], p: float) -> float:
    ordered = sorted(values)
    if not ordered:
        return float("nan")
    return ordered[min(len(ordered) - 1, int(len(ordered) * p))]


@dataclass
class Sampler:
    """Samples a process's RSS and descriptors every `every_s` in a thread (the peak matters)."""

    pid: int
    every_s: float = 0.1
    rss: list[int] = field(default_factory=list)
    fds: list[int] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                self.rss.append(rss_kb(self.pid))
                self.fds.append(fd_count(self.pid))
            except (OSError, RuntimeError):   # the process has ended
                return
            self._stop.wait(self.every_s)

    def __enter__(self) -> "Sampler":
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join(5)


class Attackers:
    """Runs each named attack in its own thread, again and again, until `seconds` have passed.
    An attack is a callable taking the deadline (time.monotonic()) and returning how many
    actions it did; exceptions it did not expect are kept in `errors`."""

    def __init__(self, attacks: dict[str, Callable[[float], int]], seconds: float) -> None:
        self.attacks = attacks
        self.seconds = seconds
        self.counts: dict[str, int] = {name: 0 for name in attacks}
        self.errors: list[str] = []
        self._threads: list[threading.Thread] = []

    def _loop(self, name: str, attack: Callable[[float], int], deadline: float) -> None:
        while time.monotonic() < deadline:
            try:
                self.counts[name] += attack(deadline)
            except Exception as exc:  # noqa: BLE001 - reported by the test, with the attack's name
                self.errors.append(f"{name}: {type(exc).__name__}: {exc}")
                return

    def __enter__(self) -> "Attackers":
        deadline = time.monotonic() + self.seconds
        for name, attack in self.attacks.items():
            thread = threading.Thread(target=self._loop, args=(name, attack, deadline), daemon=True)
            thread.start()
            self._threads.append(thread)
        return self

    def join(self) -> None:
        for thread in self._threads:
            thread.join(self.seconds + 30)

    def __exit__(self, *exc) -> None:
        self.join()


def footprint(pid: int) -> dict:
    """The server's resident memory (KiB) and open descriptors now."""
    return {"rss": rss_kb(pid), "fds": fd_count(pid)}


def soak_figures(quiet: list[float], hostile: list[float], after_latencies: list[float], base: dict,
                 sampler: Sampler, after: dict, attackers: Attackers, **extra) -> dict:
    """The figures every soak returns (latencies in seconds, RSS in KiB), plus its own `extra`."""
    return {"quiet": quiet, "hostile": hostile, "after_latencies": after_latencies, "base": base,
            "peak_rss": max(sampler.rss, default=base["rss"]), "peak_fds": max(sampler.fds, default=base["fds"]),
            "after": after, "counts": attackers.counts, "errors": attackers.errors, **extra}


def print_soak(f: dict, good: str, process: str) -> None:
    """The lines every soak bench prints: the good client's latency per phase (`good` names one of
    its rounds), the `process`'s memory and descriptors, and what each attack did."""
    for phase in ("quiet", "hostile", "after_latencies"):
        values = f[phase]
        print(f"  good {phase.split('_')[0]:8s}: {len(values):6d} {good}, "
              f"p50 {pct(values, 0.5) * 1e3:8.2f} ms  p99 {pct(values, 0.99) * 1e3:8.2f} ms")
    print(f"  {process} RSS MB: before {f['base']['rss'] / 1024:.1f}  peak {f['peak_rss'] / 1024:.1f}  "
          f"after {f['after']['rss'] / 1024:.1f}")
    print(f"  {process} descriptors: before {f['base']['fds']}  peak {f['peak_fds']}  after {f['after']['fds']}")
    print("  attacks: " + ", ".join(f"{name} {count}" for name, count in f["counts"].items()))
