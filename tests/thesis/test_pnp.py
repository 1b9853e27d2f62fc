"""PnP_Example (thesis Annex B1) + Program_Example's CBT_Connect rung, loaded exactly as
`stvm run st_src/PnP_Example.st` loads them (st_src/stvm.toml, Configuration.st: one 1 ms task),
against the TM emulator over loopback.

One full Pick-and-Place cycle: six CBT_MoveAbsolute segments in order (CmdIDs 2..7), the 2 s
waits at steps 16 and 26 (Timer_1, VM clock), frames byte for byte against the protocol spec.
"""

from __future__ import annotations

import pytest

from thesis_harness import (CHECK_LISTEN, LISTEN_OK, Emulator, Runner, frame_checksum, pose_text,
                            tag_notification, thesis_frame, thesis_project, tm_frame, tmsct_reply)

# six short, fast segments around the emulator's home pose (x, y, z); RX 180, RY 0, RZ 90
SEGMENTS = [(417.0, -122.0, 350.0), (417.0, -122.0, 340.0), (417.0, -122.0, 350.0),
            (427.0, -122.0, 350.0), (427.0, -122.0, 340.0), (427.0, -122.0, 350.0)]
PICK_PLACE_STEPS = [10, 11, 12, 13, 14, 15, 16, 20, 21, 22, 23, 24, 25, 26, 10]


def segment_params(i: int, xyz, speed=100, accel=150, blend=None) -> dict:
    x, y, z = xyz
    return {"CommandID": i + 2, "MovementCommand": "PTP", "DataFormat": "CPP_Abs", "TargetPosition.X": x,
            "TargetPosition.Y": y, "TargetPosition.Z": z, "TargetPosition.RX": 180.0, "TargetPosition.RY": 0.0,
            "TargetPosition.RZ": 90.0, "Speed": speed, "AccelTime": accel,
            "BlendingEnable": blend is not None, "BlendingValue": blend or 0}


def segment_frame(p: dict) -> bytes:
    pose = pose_text([p["TargetPosition.X"], p["TargetPosition.Y"], p["TargetPosition.Z"], 180.0, 0.0, 90.0])
    blend = str(p["BlendingValue"]) if p["BlendingEnable"] else "0"
    script = f'PTP("CPP",{pose},{p["Speed"]},{p["AccelTime"]},{blend},false)'
    if not p["BlendingEnable"]:
        script += f'\r\nQueueTag({p["CommandID"]},0)'
    return thesis_frame(p["CommandID"], script)


WATCH = {
    "Step": "PnP_Example_Instance.Prg_Step",
    "MoveExecute": "PnP_Example_Instance.MoveExecute",
    "Connected": "Cobot.Connected",
    "PnP_MoveBusy": "PnP_MoveBusy",
    "PnP_MoveDone": "PnP_MoveDone",
    "PnP_MoveError": "PnP_MoveError",
    "Ack": "PnP_Move_CmdID_Ack",
    "Busy": "PnP_Example_Instance.CBT_MoveAbsolute_Instance.Busy",
    "Done": "PnP_Example_Instance.CBT_MoveAbsolute_Instance.Done",
    "Error": "PnP_Example_Instance.CBT_MoveAbsolute_Instance.Error",
    "ErrorID": "PnP_Example_Instance.CBT_MoveAbsolute_Instance.ErrorID",
    "FB_step": "PnP_Example_Instance.CBT_MoveAbsolute_Instance.FB_step",
    "ConnError": "Connect_Error",
}


@pytest.fixture
def pnp(tmp_path):
    em = Emulator(tmp_path / "frames.jsonl")
    vm = thesis_project().start(scan="1ms")
    try:
        yield em, vm
    finally:
        vm.close()
        em.stop()


def start_pnp(em, vm, segments: list[dict]) -> tuple[Runner, int]:
    assert em.port <= 32767      # Connect_Dest_PortIP is an INT (Table 6.2.1)
    vm.set("Connect_AddressIP", "127.0.0.1")
    vm.set("Connect_Dest_PortIP", em.port)
    vm.set("Connect_Time_Out", 100)
    for i, p in enumerate(segments):
        for key, value in p.items():
            vm.set(f"PnP_MoveParameters[{i}].{key}", value)
    vm.set("Connect_Execute", True)
    r = Runner(vm, WATCH)
    r.run_until(lambda s: s["Connected"], max_scans=3000, what="Cobot.Connected")
    vm.set("PnP_Example_Execute", True)
    return r, vm.scan_count


def test_one_full_pick_and_place_cycle(pnp):
    em, vm = pnp
    segments = [segment_params(i, xyz) for i, xyz in enumerate(SEGMENTS)]
    frames = [segment_frame(p) for p in segments]
    assert all(frame_checksum(f) >= 0x10 for f in frames), "segments must have two-digit checksums (8.2)"
    r, s0 = start_pnp(em, vm, segments)
    # until the cycle is complete: step 26 -> 10, then one more scan into the next cycle
    r.run_until(lambda s: s["Step"] == 10 and r.at(s.scan - 1)["Step"] == 26, max_scans=40000,
                what="a complete cycle")
    trace = r.since(s0)

    # --- program steps, in order
    steps = [trace[0]["Step"]]
    for s in trace[1:]:
        if s["Step"] != steps[-1]:
            steps.append(s["Step"])
    assert steps == PICK_PLACE_STEPS

    # --- frames: exactly the six segments, byte for byte, in order; acknowledged in order
    assert em.rx() == [CHECK_LISTEN] + frames
    assert frames[0] == thesis_frame(2, 'PTP("CPP",+417,-122,+350,+180,+0,+90,100,150,0,false)\r\nQueueTag(2,0)')
    expected_tx = [LISTEN_OK]
    for i in range(2, 8):
        expected_tx += [tmsct_reply(f"{i},OK"), tag_notification(i)]
    assert em.tx() == expected_tx

    # --- CmdID acknowledged 2..7, one per segment, each when the segment's Done shows
    acks = [s["Ack"] for s in trace if s["PnP_MoveDone"] and not r.at(s.scan - 1)["PnP_MoveDone"]]
    assert acks == [2, 3, 4, 5, 6, 7]
    assert not any(s["PnP_MoveError"] or s["Error"] or s["ConnError"] for s in trace)

    # --- per scan, each segment: Busy ... Done (2 scans: Execute drops the scan after Done and
    # state 5 -> 6 keeps Done TRUE in that scan); the PnP_* globals are the one-scan-old copies
    # made above the FB call (sysmac.md 8.14)
    done_runs = [(start, n) for (done,), start, n in r.runs(("Done",), s0) if done]
    assert [n for _, n in done_runs] == [2] * 6
    for start, _ in done_runs:
        assert r.at(start - 1)["Busy"] and not r.at(start)["Busy"]
        assert not r.at(start)["PnP_MoveDone"] and r.at(start + 1)["PnP_MoveDone"] and r.at(start + 2)["PnP_MoveDone"]
        assert not r.at(start + 3)["PnP_MoveDone"]
        assert r.at(start + 1)["MoveExecute"] is False
    busy_runs = [(start, n) for (busy,), start, n in r.runs(("Busy",), s0) if busy]
    assert len(busy_runs) == 6

    # --- the two 2 s waits (Timer_1, PT 2000 ms on the VM clock): Prg_Step holds 16 and 26 for
    # 2002 scans - the scan that enters the step, the scan that starts the TON, 2000 ms of timing
    # (Q read above the TON call: one scan late)
    for wait_step in (16, 26):
        held = [n for (step,), _, n in r.runs(("Step",), s0) if step == wait_step]
        assert held == [2002], (wait_step, held)

    # --- the robot is at the last segment's target (whole millimetres, sysmac.md 8.13)
    pose = em.snapshot()["pose"]
    assert pose == pytest.approx([427, -122, 350, 180, 0, 90], abs=0.01)


def one_digit_segment(i: int) -> dict:
    """A blended segment whose frame has a checksum below 16#10 (found from the spec framing)."""
    for speed in (50, 100):
        for z in range(340, 356):
            for x in range(410, 425):
                p = segment_params(i, (float(x), -122.0, float(z)), speed=speed, blend=50)
                if frame_checksum(segment_frame(p)) < 0x10:
                    return p
    raise AssertionError("no one-digit segment found")


def test_cycle_hangs_on_a_one_digit_checksum_segment(pnp):
    """sysmac.md 8.2 / ERRATA Q2 at program level: the third segment's frame gets a one-digit
    checksum, the robot answers $CPERR,2,01, CBT_MoveAbsolute stays Busy in step 80 and the cycle
    never leaves step 15."""
    em, vm = pnp
    segments = [segment_params(i, xyz) for i, xyz in enumerate(SEGMENTS)]
    segments[2] = one_digit_segment(2)
    bad = segment_frame(segments[2])
    assert frame_checksum(bad) < 0x10 and bad[-5:-3] == b",*" and bad[-2:] == b"\r\n"   # ",*H\r\n"
    r, s0 = start_pnp(em, vm, segments)
    r.run_until(lambda s: s["Step"] == 15 and s["FB_step"] == 80, what="third segment sent")
    r.run_for(3000)
    assert em.rx() == [CHECK_LISTEN] + [segment_frame(p) for p in segments[:3]]
    assert em.tx()[-1] == tm_frame("CPERR", "01")
    tail = r.trace[-2500:]
    assert all(s["Step"] == 15 and s["Busy"] and s["PnP_MoveBusy"] and s["FB_step"] == 80 for s in tail)
    assert vm.get("Cobot.WaitingReturn")
    assert [s["Ack"] for s in r.since(s0) if s["PnP_MoveDone"]][::2] == [2, 3]
