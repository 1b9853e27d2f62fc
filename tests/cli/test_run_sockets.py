"""`stvm run` of a plain program (no demo) on real loopback sockets: the socket service runs
between scans there too (stvm/stdlib/sockets.py, `serve_sockets_between_scans`), the exchange
with a real TCP peer completes, and `--stats` reports the service's time apart from the scans."""

from __future__ import annotations

import socket
import threading

from core_helpers import assert_no_traceback, cli, write_st

PROGRAM = """
PROGRAM Main
VAR
    port : UINT;
    step : INT;
    conn : SktTCPConnect;
    send : SktTCPSend;
    rcv : SktTCPRcv;
    sock : _sSOCKET;
    tx : ARRAY[0..15] OF BYTE;
    rx : ARRAY[0..15] OF BYTE;
    msg : STRING[16] := 'ping';
    nbytes : UINT;
    reply : STRING[16];
END_VAR
CASE step OF
    0: conn(Execute := TRUE, SrcTcpPort := 0, DstAdr := '127.0.0.1', DstTcpPort := port, Socket => sock);
       IF conn.Done THEN step := 1; END_IF;
       IF conn.Error THEN step := 99; END_IF;
    1: nbytes := ToAryByte(msg, _eBYTE_ORDER#_LOW_HIGH, tx[0]);
       send(Execute := TRUE, Socket := sock, SendDat := tx[0], Size := LEN(msg));
       IF send.Done THEN step := 2; END_IF;
       IF send.Error THEN step := 99; END_IF;
    2: rcv(Execute := TRUE, Socket := sock, TimeOut := 0, Size := 16, RcvDat := rx[0]);
       IF rcv.Done THEN reply := AryToString(rx[0], rcv.RcvSize); step := 3; END_IF;
       IF rcv.Error THEN step := 99; END_IF;
END_CASE;
END_PROGRAM
"""


class EchoPeer:
    """A loopback TCP server answering every read with `pong:` and what it read."""

    def __init__(self) -> None:
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.received = b""
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        conn, _ = self.listener.accept()
        with conn:
            data = conn.recv(64)
            self.received = data
            conn.sendall(b"pong:" + data)
            conn.recv(64)   # until the VM closes the socket at the end of the run

    def close(self) -> None:
        self.listener.close()


def test_a_plain_run_talks_over_real_sockets_with_the_service_between_scans():
    peer = EchoPeer()
    try:
        main_st = write_st(PROGRAM, "sockets_main.st")
        rc, out, err = cli(["run", main_st, "--realtime", "--scan", "1ms", "--set", f"Main.port={peer.port}",
                            "--until", "Main.step >= 3", "--duration", "10s", "--stats",
                            "--print", "Main.step", "--print", "Main.reply", "--no-cache"])
        assert_no_traceback(err)
        assert rc == 0, err
        assert "Main.step = 3" in out
        assert "Main.reply = 'pong:ping'" in out
        assert peer.received == b"ping"
        assert "socket service us (between scans, not in the scan time):" in out
    finally:
        peer.close()


def test_a_run_without_socket_blocks_has_no_socket_service():
    main_st = write_st("PROGRAM Main VAR n : INT; END_VAR n := n + 1; END_PROGRAM\n", "plain_main.st")
    rc, out, err = cli(["run", main_st, "--cycles", "3", "--stats", "--no-cache"])
    assert rc == 0, err
    assert "scans: 3" in out
    assert "socket service" not in out
