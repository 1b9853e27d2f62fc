"""The real PyPI clients, unchanged, against the emulator over 127.0.0.1 (spec §10)."""

from __future__ import annotations

import asyncio

import pytest

from emu_helpers import wait_until

import pytmrobot  # noqa: F401 (the test extra installs both: a missing one fails here, never skips)
import techmanpy


@pytest.fixture
def techman_port(fast_server):
    # techmanpy has no port argument: the port is a class attribute (spec §10.1).
    old = (techmanpy.TMSCT_client.PORT, techmanpy.TMSTA_client.PORT)
    techmanpy.TMSCT_client.PORT = techmanpy.TMSTA_client.PORT = fast_server.port
    yield fast_server
    techmanpy.TMSCT_client.PORT, techmanpy.TMSTA_client.PORT = old


def test_techmanpy_full_session(techman_port) -> None:
    server = techman_port

    async def session() -> None:
        async with techmanpy.connect_sta(robot_ip="127.0.0.1") as sta:
            assert await sta.is_listen_node_active() is True
            assert await sta.get_queue_tag_status(1) is None  # never queued -> "none"
        async with techmanpy.connect_sct(robot_ip="127.0.0.1", suppress_warns=True) as conn:
            await conn.move_to_joint_angles_ptp([0, 0, 90, 0, 90, 0], 0.10, 200)
            await conn.move_to_point_line([417.5, -122.3, 343.9, 180, 0, 90], 100, 200, speed_is_velocity=True)
            await conn.set_queue_tag(1, wait_for_completion=True)  # returns once tag 1 was reached
            trans = conn.start_transaction()
            trans.set_base("RobotBase")
            trans.set_tcp("NOTOOL")
            trans.move_to_point_ptp([400, -100, 350, 180, 0, 90], 0.5, 200, 0.2)
            trans.move_on_circle([420, -50, 350, 180, 0, 90], [400, 0, 350, 180, 0, 90], 0.5, 200, arc_angle=0)
            trans.move_to_relative_point_line([0, 0, 10, 0, 0, 0], 0.2, 100, relative_to_tcp=True)
            trans.move_to_relative_point_ptp([0, 0, 10, 0, 0, 0], 0.2, 100)
            trans.move_to_point_path([400, -50, 360, 180, 0, 90], 100, 200)
            trans.set_queue_tag(2)
            await trans.submit()
            await conn.pause_project()
            await conn.resume_project()
            await conn.wait_for_queue_tag(2, 10000)
            with pytest.raises(techmanpy.TMSCTError):
                await conn._execute(("NoSuchFunction", []))  # ERROR;1
            await conn.stop_motion()
        async with techmanpy.connect_sta(robot_ip="127.0.0.1") as sta:
            assert await sta.get_queue_tag_status(2) is True
        async with techmanpy.connect_sct(robot_ip="127.0.0.1") as conn:
            await conn.exit_listen()
        async with techmanpy.connect_sta(robot_ip="127.0.0.1") as sta:
            assert await sta.is_listen_node_active() is False
        async with techmanpy.connect_sct(robot_ip="127.0.0.1") as conn:
            # Outside the node: CPERR F1 -> TMProtocolError "Listen Node is not active" (spec §6).
            with pytest.raises(techmanpy.TMProtocolError, match="not active"):
                await conn.pause_project()

    asyncio.run(asyncio.wait_for(session(), 30))
    assert server.snapshot()["state"] in ("RUNNING", "IN_NODE")


def test_pytmrobot_full_session(fast_server) -> None:
    from pytmrobot import CartPoint, JointPoint, TMRobot
    from pytmrobot.exceptions import TMScriptError
    from pytmrobot.types import SpeedUnit

    with TMRobot("127.0.0.1", port=fast_server.port, timeout=10) as robot:
        robot.move.ptp(CartPoint(400, -100, 350, 180, 0, 90), speed=30)    # QueueTag(n,1): OK = done
        assert robot.state.tcp_position == pytest.approx((400, -100, 350, 180, 0, 90), abs=0.05)
        robot.move.ptp(JointPoint(0, 0, 90, 0, 90, 0), wait=False)
        robot.move.wait_motion()                                          # polls TMSTA 01,<n>
        assert robot.state.joint_angles == pytest.approx((0, 0, 90, 0, 90, 0), abs=1e-3)
        robot.move.line(CartPoint(450, -100, 350, 180, 0, 90), speed=150)  # "CDP" (TMflow 2.x)
        robot.move.line(CartPoint(450, -50, 350, 180, 0, 90), speed=50, speed_unit=SpeedUnit.PERCENT)
        robot.move.circle(CartPoint(420, -50, 350, 180, 0, 90), CartPoint(400, 0, 350, 180, 0, 90))
        robot.move.line_relative(CartPoint(0, 0, 10, 0, 0, 0), speed=50)
        robot.move.ptp_relative(CartPoint(0, 0, -10, 0, 0, 0), speed=20)
        robot.change_base("RobotBase")
        robot.change_tcp("NOTOOL")
        robot.change_load(1.5)
        robot.sleep(20)
        assert robot.state.tcp_position[2] == pytest.approx(350, abs=0.05)
        assert robot.run_script(["NoSuch()"]) is False                    # ERROR
        with pytest.raises(TMScriptError):
            robot.move.ptp(CartPoint(2000, 0, 0, 180, 0, 0), speed=30)      # unreachable -> ERROR
        robot.stop(0)                                                     # priority StopAndClearBuffer(0)
        robot.exit_listen(True)                                           # priority ScriptExit(1)
    assert wait_until(lambda: fast_server.snapshot()["connections"] == [])


def test_pytmrobot_low_level_client(fast_server) -> None:
    from pytmrobot._protocol import TMClient

    client = TMClient("127.0.0.1", fast_server.port)
    client.connect()
    try:
        client.wait_for_listen_node()
        # QueueTag(1,1): the OK comes after the tag notification, which send_script skips.
        assert client.send_script("1", ['PTP("JPP",0,0,90,0,90,45,50,200,0,false)', "QueueTag(1,1)"])
        assert client.query_listen_mode() is True
        client.wait_queue_tag(1, poll_interval=0.01)  # already reached: the first poll says true
        client.exit_listen(False)                                         # ScriptExit(0): Fail path
        assert client.query_listen_mode() is False
        # After reenter_delay_ms the flow is back in the node: wait_for_listen_node sees the entry
        # message (spec §1.7).
        client.wait_for_listen_node()
    finally:
        client.disconnect()
