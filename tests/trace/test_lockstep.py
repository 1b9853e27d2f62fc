"""Lockstep: the in-process emulator behind the socket FBs, on the VM clock."""

from __future__ import annotations

from pathlib import Path

import pytest

from emulator import parse_faults
from stvm.lockstep import LockstepTransport, start_lockstep

LISTEN = Path(__file__).parent / "st" / "listen_check.st"


@pytest.fixture(scope="module")
def project():
    from stvm.project import load
    return load([LISTEN])


def run(project, cycles=40, **options):
    vm, transport = start_lockstep(project, scan="1ms", **options)
    vm.set("Main.go", True)
    vm.run(cycles=cycles)
    return vm, transport


def test_latency_defaults_to_one_scan(project):
    vm, transport = run(project, cycles=1)
    assert transport.latency_ns == vm.base_ns == 1_000_000
    vm, transport = run(project, cycles=1, latency_scans=3)
    assert transport.latency_ns == 3_000_000
    vm, transport = run(project, cycles=1, latency_ns=250_000)
    assert transport.latency_ns == 250_000


@pytest.mark.parametrize(("latency", "connected", "replied"), [(0, 3, 7), (1, 4, 8), (2, 6, 11), (5, 12, 23)])
def test_round_trips_take_the_modelled_latency(project, latency, connected, replied):
    # the connect starts in scan 2 (counted from 1): SYN + SYN/ACK take two latencies, and the
    # FBs see a completion one call later at the earliest (skt_min_latency_calls = 1)
    vm, transport = run(project, latency_scans=latency)
    assert vm.get("Main.step") == 4
    assert (vm.get("Main.connected_scan"), vm.get("Main.reply_scan")) == (connected, replied)
    assert vm.get("Main.reply") == b"$TMSTA,15,00,true,Listen1,*79\r\n"
    assert [f.direction for f in transport.frames] == ["rx", "tx"]


def test_refused_connection_is_an_fb_error(project):
    vm, _ = run(project, faults=parse_faults(["refuse"]))
    assert vm.get("Main.step") == 99
    assert vm.get("Main.conn.ErrorID") == 0x2003


def test_fault_injected_during_the_run(project):
    vm, transport = start_lockstep(project, scan="1ms")
    vm.set("Main.go", True)
    vm.run(cycles=6)
    assert transport.link.robot.accepting
    transport.inject_fault("stop:2")        # the project stops 2 ms from now: sockets closed
    vm.run(cycles=4)
    assert not transport.link.robot.accepting
    transport.clear_faults()
    assert transport.link.core.faults == parse_faults([])


def test_attach_checks_its_vm(project):
    transport = LockstepTransport()
    other = project.start(scan="1ms")
    with pytest.raises(ValueError, match="another transport"):
        transport.attach(other)
    vm = project.start(scan="1ms", transport=transport)
    transport.attach(vm)
    with pytest.raises(ValueError, match="already attached"):
        transport.attach(vm)


def test_identical_runs_give_identical_frames(project):
    first = run(project)[1].frames
    second = run(project)[1].frames
    assert first == second and first


def test_several_robots_each_reached_at_its_own_address():
    """`add_robot(host, port)`: connections to that address reach that robot, anything else the
    default robot; all are stepped on the VM clock and their frames carry the robot's index."""
    import stvm
    source = Path(__file__).parent / "st" / "two_robots.st"
    transport = LockstepTransport(latency_scans=1)
    second = transport.add_robot("127.0.0.1", 6000)
    with pytest.raises(ValueError, match="has a robot already"):
        transport.add_robot("127.0.0.1", 6000)
    vm = stvm.load([source]).start(scan="1ms", transport=transport)
    transport.attach(vm)
    with pytest.raises(ValueError, match="before attach"):
        transport.add_robot("127.0.0.1", 6001)
    vm.set("Main.go", True)
    vm.run(cycles=40)
    assert transport.robots == [transport.link, second]
    assert second.robot.connections and transport.link.robot.connections
    by_robot = {(f.robot, f.direction) for f in transport.frames}
    assert by_robot == {(0, "rx"), (0, "tx"), (1, "rx"), (1, "tx")}
    assert vm.get("Main.replies") == 2


def test_polling_shortcut_matches_the_socket_table():
    """`LockstepTransport.poll`/`pending` (a shortcut while nothing arrives) give what
    `SocketTable`'s own give, scan by scan: connecting, established and idle, a reply arriving,
    the robot's project stopping (its sockets closed)."""
    from emulator import encode
    from stvm.stdlib.sockets import SocketTable
    fast, plain = LockstepTransport(), LockstepTransport()
    seen = {id(fast): [], id(plain): []}
    for transport, poll, pending in ((fast, fast.poll, fast.pending),
                                     (plain, lambda h, t: SocketTable.poll(plain, h, t),
                                      lambda h: SocketTable.pending(plain, h))):
        handle = transport.open_connection(0, "127.0.0.1", 5890, 0)
        for scan in range(40):
            now = scan * 1_000_000
            if scan == 8:
                transport.send(handle, encode("TMSTA", "00"))
            if scan == 20:
                transport.inject_fault("stop:3")
            seen[id(transport)].append((poll(handle, now), pending(handle)))
            if scan == 12:
                transport.receive(handle, 100)
            transport.link.advance_to(now + 1_000_000)
    assert seen[id(fast)] == seen[id(plain)]
    states = [state for state, _ in seen[id(fast)]]
    assert {"connecting", "established", "peer_closed"} <= set(states)
    assert any(count for _, count in seen[id(fast)])      # the reply was buffered
