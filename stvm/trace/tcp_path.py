"""The robot's TCP path during a recorded lockstep run, drawn as the thesis draws its PnP cycle
(Figure 5.4.8): top view (X-Y), side view (X-Z) and front view (Y-Z), with the points where
the robot stopped.

    stvm trace st_src/PnP_Example.st --scenario st_src/scenarios/golden_pnp_cycle.toml -o pnp_path.svg

`TcpPathRecorder` samples the in-process robot (`emulator.Robot.snapshot()`) every `every_ns` of VM
time at the end of a scan; `render_tcp_path` writes `.svg` or `.png` with matplotlib (the `plot`
extra: `pip install 'stvm[plot]'`), deterministic for the same run (no dates in the SVG).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from stvm.trace.writers import TraceFormatError

PICTURE_SUFFIXES = (".svg", ".png")
SAMPLE_NS = 10_000_000     # 100 samples a second of VM time: smooth at PnP speeds


@dataclass
class TcpPathRecorder:
    transport: object
    every_ns: int = SAMPLE_NS
    points: list[tuple[int, float, float, float, bool]] = field(default_factory=list)   # t, x, y, z, moving
    used: bool = False   # whether the program connected to the robot during the run
    _next_ns: int = 0

    def sample(self, vm) -> None:
        if vm.now_ns < self._next_ns:
            return
        self._next_ns = vm.now_ns + self.every_ns
        snap = self.transport.link.robot.snapshot()
        if snap.get("connections") or snap.get("moving"):
            self.used = True
        x, y, z = (float(v) for v in snap["pose"][:3])
        self.points.append((vm.now_ns, x, y, z, bool(snap["moving"])))

    def stops(self, tolerance_mm: float = 1.0) -> list[tuple[float, float, float]]:
        """Distinct points where a motion ended (moving → still), in the order first reached."""
        found: list[tuple[float, float, float]] = []
        for before, after in zip(self.points, self.points[1:]):
            if before[4] and not after[4]:
                point = after[1:4]
                if all(max(abs(a - b) for a, b in zip(point, seen)) > tolerance_mm for seen in found):
                    found.append(point)
        return found


class PlotUnavailable(RuntimeError):
    """matplotlib is not installed."""


class NoPath(TraceFormatError):
    """The run never used the robot: there is no path to draw."""


def render_tcp_path(recorder: TcpPathRecorder, out: str | Path, title: str = "TCP path") -> Path:
    """Write the top and side views of the recorded path to `out` (.svg or .png)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as exc:
        raise PlotUnavailable("TCP path pictures need matplotlib: pip install 'stvm[plot]'") from exc
    out = Path(out)
    if out.suffix.lower() not in PICTURE_SUFFIXES:
        raise ValueError(f"{out}: a TCP path picture is .svg or .png")
    if not recorder.used:
        # the robot's home pose alone would be drawn as "start" of an empty path (issue 34 item 12)
        raise NoPath(f"{out}: the program never connected to the robot during the run, so there is "
                     f"no TCP path to draw (record a run that moves the robot, e.g. with a scenario)")
    coords = {"X": [p[1] for p in recorder.points], "Y": [p[2] for p in recorder.points],
              "Z": [p[3] for p in recorder.points]}
    stops = recorder.stops()
    plt.rcParams["svg.hashsalt"] = "stvm"          # stable ids: the same run gives the same file
    fig, panels = plt.subplots(1, 3, figsize=(13.5, 4.6))
    views = (("X", "Y", "top view (X-Y)"), ("X", "Z", "side view (X-Z)"), ("Y", "Z", "front view (Y-Z)"))
    for axes, (h, v, name) in zip(panels, views):
        axes.plot(coords[h], coords[v], color="#1f5fa8", linewidth=1.2, label="TCP path")
        if recorder.points:
            axes.plot(coords[h][0], coords[v][0], "o", color="#e65100", label="start")
        for i, stop in enumerate(stops, start=1):
            point = dict(zip("XYZ", stop))
            axes.plot(point[h], point[v], "s", markerfacecolor="none", markeredgecolor="#2e7d32", markersize=8)
            axes.annotate(str(i), (point[h], point[v]), textcoords="offset points", xytext=(6, 4), color="#2e7d32")
        axes.set_xlabel(f"{h} (mm)")
        axes.set_ylabel(f"{v} (mm)")
        axes.set_aspect("equal", adjustable="datalim")
        axes.grid(True, color="#dde3ea")
        axes.set_title(name)
    panels[0].legend(loc="best", fontsize="small")
    fig.suptitle(f"{title}: {len(recorder.points)} samples, {len(stops)} stop points (squares)")
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    metadata = {"Date": None} if out.suffix.lower() == ".svg" else {"Software": None}
    fig.savefig(out, format=out.suffix.lower()[1:], dpi=110, metadata=metadata)
    plt.close(fig)
    return out
