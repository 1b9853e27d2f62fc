"""Outputs and status are read-only for the HMI too (issue 32 item 11), whatever a page maps:
the limits table's rule, the built-in status names and the `@outputs` switch that opens them."""

from __future__ import annotations

import threading

import httpx

import stvm
from small_project import SOURCE, TEST_PAGE, write_project
from stvm.frontend import VariableBridge
from stvm.frontend.limits import LimitTable
from stvm.hmi import HmiServer, load_pages
from stvm.hmi.cli import page_files

BUSY_PAGE = TEST_PAGE.replace('''[[area.widget]]
kind = "note"''', '''[[area.widget]]
kind = "toggle"
var = "Drive_Busy"
label = "Busy"

[[area.widget]]
kind = "note"''')


def _serve(tmp_path, limits_toml: str = ""):
    main = write_project(tmp_path, BUSY_PAGE)
    main.write_text(SOURCE.replace("Secret : INT;", "Secret : INT; Drive_Busy : BOOL;"))
    manifest = tmp_path / "stvm.toml"
    manifest.write_text(manifest.read_text() + limits_toml)
    project = stvm.load([str(main)])
    vm = project.start(scan="1ms", realtime=True)
    bridge = VariableBridge(vm)
    files, start = page_files(project)
    server = HmiServer(load_pages(files, bridge.type_of, start), bridge, port=0,
                       limit_table=LimitTable.for_project(project, vm)).start()
    stop = threading.Event()
    thread = threading.Thread(target=lambda: vm.run(until=stop.is_set), daemon=True)
    thread.start()

    def close():
        stop.set()
        thread.join(5)
        server.stop()
    return httpx.Client(base_url=f"http://127.0.0.1:{server.port}", timeout=10), vm, close


def test_a_status_a_page_maps_is_refused_and_not_listed_writable(tmp_path):
    http, vm, close = _serve(tmp_path)
    try:
        refused = http.post("/api/vars", json={"Drive_Busy": "TRUE"})
        assert refused.status_code == 403
        assert refused.json()["error"] == "Busy: read-only (an output or status of the controller)"
        assert vm["Drive_Busy"] is False
        assert "Drive_Busy" not in http.get("/api/pages").json()["writable"]
        assert http.post("/api/vars", json={"Start": "TRUE"}).status_code == 200   # a command still is
    finally:
        http.close()
        close()


def test_the_outputs_switch_opens_them(tmp_path):
    http, vm, close = _serve(tmp_path, '\n[limits]\n"@outputs" = { writable = true }\n')
    try:
        assert http.post("/api/vars", json={"Drive_Busy": "TRUE"}).status_code == 200
        assert "Drive_Busy" in http.get("/api/pages").json()["writable"]
    finally:
        http.close()
        close()
