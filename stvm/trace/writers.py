"""Trace files, chosen by suffix: `.jsonl` (the golden format), `.csv`, `.vcd`, `.json` (WaveDrom).

Every writer is deterministic (no dates, no absolute paths, fixed key order), so a run written
twice gives byte-identical files. `.jsonl` and `.csv` are read back by `read_trace` for golden
comparison; `.vcd` and `.json` are for viewing (GTKWave, WaveDrom).

JSON lines (`.jsonl`), one object per line, in scan order::

    {"format": "stvm-trace", "version": 1, "scan_ns": 1000000, "scans": 9000,
     "signals": [{"name": "Cobot.Connected", "type": "BOOL", "kind": "bool", "bits": 0}, …],
     "meta": {"files": […], "scenario": "…", "latency_ns": 1000000, "watch": […]}}
    {"scan": 0, "t_ns": 0, "values": {"Cobot.Connected": "FALSE", …}}        every signal
    {"scan": 22, "t_ns": 22000000, "values": {"Cobot.Connected": "TRUE"}}    changes only
    {"scan": 23, "t_ns": 23000000, "event": "set PnP_Example_Execute=TRUE"}
    {"scan": 35, "t_ns": 36000000, "frame": "rx", "conn": 1, "data": "$TMSCT,69,2,…"}

Values are IEC literals; `t_ns` of a value line is the VM time of its scan (its values are those
at the end of the scan); a frame's `t_ns` is the emulator time the robot received or sent it.

CSV (`.csv`): header `scan,t_ns,<signal>…,events,frames`; a row for scan 0, for every scan with a
change, event or frame, and for the last scan; each row holds every signal's value then (so it
plots as is). `events`/`frames` cells join the scan's items with ` | `; frames are written
`rx#1 <frame>` with ST escapes (`$R$L`).

VCD (`.vcd`, timescale 1 ns): one variable per signal, scopes from the path (`Cobot.Socket.Handle`
is `Handle` in scope `Cobot.Socket`); BOOL → wire, integers → integer of their width, REAL → real,
everything else → string (the IEC literal); frames go to the string variables `emulator.rx` /
`emulator.tx`, events to `stvm.event`.

WaveDrom (`.json`): one column per scan in which something changed (not to scale: the top lane
gives each column's scan number), at most `max_columns` columns; BOOLs as levels, other values as
labelled data. `write_trace(…, svg=True)` also renders `<name>.svg` when the `wavedrom` package is
installed.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

from stvm.trace.model import EventEntry, FrameEntry, SignalInfo, Trace, escape_frame, unescape_frame

FORMAT_NAME = "stvm-trace"
FORMAT_VERSION = 1
SUFFIXES = (".jsonl", ".csv", ".vcd", ".json")


class TraceFormatError(ValueError):
    """A trace file that cannot be read (wrong suffix, not a stvm trace, damaged)."""


def write_trace(trace: Trace, path: str | Path, svg: bool = False, max_columns: int = 120) -> list[Path]:
    """Write `trace` in the format its suffix names; returns the files written."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".jsonl":
        text = to_jsonl(trace)
    elif suffix == ".csv":
        text = to_csv(trace)
    elif suffix == ".vcd":
        text = to_vcd(trace)
    elif suffix == ".json":
        text = json.dumps(to_wavedrom(trace, max_columns), indent=1) + "\n"
    else:
        raise TraceFormatError(f"{path}: unknown trace format {suffix!r} (use {', '.join(SUFFIXES)})")
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", encoding="utf-8", newline="") as fh:
        fh.write(text)
    written = [path]
    if svg:
        written.append(write_svg(trace, path.with_suffix(".svg"), max_columns))
    return written


# --- JSON lines -------------------------------------------------------------------------------

def _header(trace: Trace) -> dict:
    return {"format": FORMAT_NAME, "version": FORMAT_VERSION, "scan_ns": trace.scan_ns, "scans": trace.scans,
            "signals": [{"name": s.name, "type": s.type, "kind": s.kind, "bits": s.bits} for s in trace.signals],
            "meta": trace.meta}


def _timeline(trace: Trace):
    """(scan, order, payload) items in file order: values, then events, then frames per scan."""
    items: list[tuple[int, int, int, object]] = []
    by_scan: dict[int, list[tuple[int, str]]] = {}
    for scan, index, value in trace.changes:
        by_scan.setdefault(scan, []).append((index, value))
    for scan, pairs in by_scan.items():
        items.append((scan, 0, 0, pairs))
    for n, event in enumerate(trace.events):
        items.append((event.scan, 1, n, event))
    for n, frame in enumerate(trace.frames):
        items.append((frame.scan, 2, n, frame))
    items.sort(key=lambda item: item[:3])
    return items


def to_jsonl(trace: Trace) -> str:
    dump = lambda obj: json.dumps(obj, ensure_ascii=False, separators=(", ", ": "))  # noqa: E731
    lines = [dump(_header(trace))]
    if trace.scans:
        lines.append(dump({"scan": 0, "t_ns": 0, "values": {s.name: v for s, v in zip(trace.signals, trace.initial)}}))
    names = [s.name for s in trace.signals]
    for scan, order, _, payload in _timeline(trace):
        if order == 0:
            lines.append(dump({"scan": scan, "t_ns": trace.time_of(scan), "values": {names[i]: v for i, v in payload}}))
        elif order == 1:
            lines.append(dump({"scan": scan, "t_ns": trace.time_of(scan), "event": payload.text}))
        else:
            lines.append(dump({"scan": scan, "t_ns": payload.t_ns, "frame": payload.direction,
                               "conn": payload.conn, "data": payload.data}))
    return "\n".join(lines) + "\n"


def from_jsonl(text: str, name: str = "<trace>") -> Trace:
    lines = [line for line in text.splitlines() if line.strip()]
    if not lines:
        raise TraceFormatError(f"{name}: empty trace file")
    try:
        header = json.loads(lines[0])
    except json.JSONDecodeError as exc:
        raise TraceFormatError(f"{name}:1: not JSON: {exc}") from exc
    if header.get("format") != FORMAT_NAME:
        raise TraceFormatError(f"{name}:1: not a stvm trace (no \"format\": \"{FORMAT_NAME}\")")
    if header.get("version") != FORMAT_VERSION:
        raise TraceFormatError(f"{name}:1: trace format version {header.get('version')} (this stvm reads {FORMAT_VERSION})")
    signals = [SignalInfo(s["name"], s.get("type", "?"), s.get("kind", "?"), s.get("bits", 0)) for s in header["signals"]]
    index = {s.name: i for i, s in enumerate(signals)}
    trace = Trace(signals=signals, scan_ns=int(header["scan_ns"]), scans=int(header["scans"]),
                  initial=[""] * len(signals), meta=header.get("meta", {}))
    first = True
    for lineno, line in enumerate(lines[1:], start=2):
        try:
            obj = json.loads(line)
            scan = int(obj["scan"])
            if "values" in obj:
                if first and scan == 0:
                    for key, value in obj["values"].items():
                        trace.initial[index[key]] = value
                    first = False
                else:
                    for key, value in obj["values"].items():
                        trace.changes.append((scan, index[key], value))
            elif "event" in obj:
                trace.events.append(EventEntry(scan, obj["event"]))
            elif "frame" in obj:
                trace.frames.append(FrameEntry(scan, int(obj["t_ns"]), obj["frame"], int(obj["conn"]), obj["data"]))
        except (json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
            raise TraceFormatError(f"{name}:{lineno}: bad trace line: {exc}") from exc
    trace.changes.sort(key=lambda c: (c[0], c[1]))
    return trace


# --- CSV --------------------------------------------------------------------------------------

def to_csv(trace: Trace) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["scan", "t_ns"] + [s.name for s in trace.signals] + ["events", "frames"])
    if not trace.scans:
        return out.getvalue()
    current = list(trace.initial)
    events: dict[int, list[str]] = {}
    frames: dict[int, list[str]] = {}
    for event in trace.events:
        events.setdefault(event.scan, []).append(event.text.replace("|", "/"))
    for frame in trace.frames:
        frames.setdefault(frame.scan, []).append(frame.text())
    by_scan: dict[int, list[tuple[int, str]]] = {}
    for scan, index, value in trace.changes:
        by_scan.setdefault(scan, []).append((index, value))
    rows = sorted({0, trace.scans - 1} | set(by_scan) | set(events) | set(frames))
    for scan in rows:
        for index, value in by_scan.get(scan, ()):
            current[index] = value
        writer.writerow([scan, trace.time_of(scan)] + current +
                        [" | ".join(events.get(scan, [])), " | ".join(frames.get(scan, []))])
    return out.getvalue()


def from_csv(text: str, name: str = "<trace>") -> Trace:
    reader = csv.reader(io.StringIO(text))
    try:
        header = next(reader)
    except StopIteration:
        raise TraceFormatError(f"{name}: empty CSV trace") from None
    if header[:2] != ["scan", "t_ns"] or header[-2:] != ["events", "frames"]:
        raise TraceFormatError(f"{name}:1: not a stvm trace CSV (header scan,t_ns,…,events,frames)")
    names = header[2:-2]
    signals = [SignalInfo(n, "?", "?") for n in names]
    trace = Trace(signals=signals, scan_ns=0, scans=0, initial=[""] * len(names))
    previous: list[str] | None = None
    last_scan = -1
    for lineno, row in enumerate(reader, start=2):
        if len(row) != len(header):
            raise TraceFormatError(f"{name}:{lineno}: {len(row)} cells, header has {len(header)}")
        scan, t_ns = int(row[0]), int(row[1])
        if scan and not trace.scan_ns:
            trace.scan_ns = t_ns // scan
        values = row[2:-2]
        if previous is None:
            trace.initial = list(values)
        else:
            trace.changes += [(scan, i, v) for i, (v, p) in enumerate(zip(values, previous)) if v != p]
        previous = values
        for text in filter(None, row[-2].split(" | ")):
            trace.events.append(EventEntry(scan, text))
        for text in filter(None, row[-1].split(" | ")):
            head, _, data = text.partition(" ")
            direction, _, conn = head.partition("#")
            # Choice: CSV keeps no frame times; the scan's start stands in (not compared)
            trace.frames.append(FrameEntry(scan, scan * trace.scan_ns, direction, int(conn or 0), unescape_frame(data)))
        last_scan = scan
    trace.scans = last_scan + 1
    return trace


# --- VCD --------------------------------------------------------------------------------------

def _number(text: str, kind: str) -> object:
    if kind == "bool":
        return 1 if text == "TRUE" else 0
    if kind == "real":
        return float(text)
    return int(text)


def to_vcd(trace: Trace) -> str:
    try:
        from vcd import VCDWriter
    except ImportError as exc:
        raise TraceFormatError(".vcd output needs the pyvcd package (pip install pyvcd)") from exc
    out = io.StringIO()
    # date="" keeps the file reproducible (pyvcd would stamp the current date)
    with VCDWriter(out, timescale="1 ns", date="", version="stvm trace", comment="stvm golden trace") as writer:
        variables = []
        for signal in trace.signals:
            scope, _, leaf = signal.name.rpartition(".")
            scope = scope or "globals"
            kind = signal.kind
            if kind == "bool":
                var = writer.register_var(scope, leaf, "wire", size=1)
            elif kind == "int" and signal.bits:
                var = writer.register_var(scope, leaf, "integer", size=signal.bits)
            elif kind == "real":
                var = writer.register_var(scope, leaf, "real")
            else:
                var = writer.register_var(scope, leaf, "string")
            variables.append(var)
        rx = writer.register_var("emulator", "rx", "string")
        tx = writer.register_var("emulator", "tx", "string")
        event_var = writer.register_var("stvm", "event", "string")

        def change(var, t_ns: int, index: int, text: str) -> None:
            signal = trace.signals[index]
            if signal.kind == "bool" or (signal.kind == "int" and signal.bits) or signal.kind == "real":
                value = _number(text, signal.kind)
                if signal.kind == "int":
                    value = int(value) & ((1 << signal.bits) - 1)   # two's complement in the vector
                writer.change(var, t_ns, value)
            else:
                writer.change(var, t_ns, text.rpartition("#")[2] if signal.kind == "enum" else text)

        if trace.scans:
            for index, text in enumerate(trace.initial):
                change(variables[index], 0, index, text)
        items: list[tuple[int, int, int, object]] = []
        for n, (scan, index, text) in enumerate(trace.changes):
            items.append((trace.time_of(scan), 0, n, (index, text)))
        for n, event in enumerate(trace.events):
            items.append((trace.time_of(event.scan), 1, n, event))
        for n, frame in enumerate(trace.frames):
            items.append((frame.t_ns, 2, n, frame))
        items.sort(key=lambda item: item[:3])
        for t_ns, order, _, payload in items:
            if order == 0:
                index, text = payload
                change(variables[index], t_ns, index, text)
            elif order == 1:
                writer.change(event_var, t_ns, payload.text)
            else:
                writer.change(rx if payload.direction == "rx" else tx, t_ns, escape_frame(payload.data))
    return out.getvalue()


# --- WaveDrom ---------------------------------------------------------------------------------

def _short(text: str, kind: str) -> str:
    if kind == "enum":
        return text.rpartition("#")[2]
    return text


def to_wavedrom(trace: Trace, max_columns: int = 120) -> dict:
    """A WaveDrom document (`{"signal": […], "head": …, "foot": …}`) of the trace."""
    frame_scans: dict[int, list[FrameEntry]] = {}
    for frame in trace.frames:
        frame_scans.setdefault(frame.scan, []).append(frame)
    columns = sorted({0} | {scan for scan, _, _ in trace.changes} | set(frame_scans)
                     | {event.scan for event in trace.events}) if trace.scans else []
    truncated = len(columns) > max_columns
    columns = columns[:max_columns]
    lanes = [{"name": "scan", "wave": "=" * len(columns), "data": [str(c) for c in columns]}]
    for index, signal in enumerate(trace.signals):
        wave, data, previous = [], [], None
        for column in columns:
            value = trace.value_at(index, column)
            if value == previous:
                wave.append(".")
            elif signal.kind == "bool":
                wave.append("1" if value == "TRUE" else "0")
            else:
                wave.append("=")
                data.append(_short(value, signal.kind))
            previous = value
        lane: dict = {"name": signal.name, "wave": "".join(wave)}
        if data:
            lane["data"] = data
        lanes.append(lane)
    if trace.frames:
        for direction, title in (("rx", "robot rx"), ("tx", "robot tx")):
            wave, data, idle = [], [], False
            for column in columns:
                frames = [f for f in frame_scans.get(column, []) if f.direction == direction]
                if frames:
                    wave.append("=")
                    data.append(" ".join(_frame_label(f) for f in frames))
                    idle = False
                else:
                    wave.append("." if idle else "x")   # "x": no frame in this column
                    idle = True
            lanes.append({"name": title, "wave": "".join(wave), "data": data})
    last = columns[-1] if columns else 0
    doc = {"signal": lanes,
           "head": {"text": f"stvm trace: scans 0..{last} of {trace.scans}, scan {trace.scan_ns / 1e6:g} ms"},
           "config": {"hscale": 2 if len(columns) <= 40 else 1}}
    if truncated:
        doc["foot"] = {"text": f"first {max_columns} change points only"}
    return doc


def _frame_label(frame: FrameEntry) -> str:
    """`TMSCT 2`, `TMSCT 2 OK`, `TMSTA 01`, `CPERR 01`: header, id or code, and a verdict."""
    parts = frame.data.strip().lstrip("$").split(",")
    if len(parts) < 3:
        return parts[0][:8]
    label = f"{parts[0]} {parts[2]}"
    if len(parts) > 3 and (parts[3] == "OK" or parts[3].startswith("ERROR")):
        label += " " + parts[3].split(";")[0]
    return label


def write_svg(trace: Trace, path: str | Path, max_columns: int = 120) -> Path:
    try:
        import wavedrom
    except ImportError as exc:
        raise TraceFormatError("--svg needs the wavedrom package (pip install wavedrom)") from exc
    path = Path(path)
    drawing = wavedrom.render(json.dumps(to_wavedrom(trace, max_columns)))
    drawing.saveas(str(path))
    return path


# --- reading ----------------------------------------------------------------------------------

def read_trace(path: str | Path) -> Trace:
    """A trace file written by `write_trace` (`.jsonl` or `.csv`)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".jsonl", ".csv"):
        raise TraceFormatError(f"{path}: golden traces are .jsonl or .csv files, not {suffix!r}")
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise TraceFormatError(f"{path}: cannot read: {exc.strerror or exc}") from exc
    if suffix == ".jsonl":
        return from_jsonl(text, str(path))
    return from_csv(text, str(path))
