"""Operator HMI: the project's touch-screen pages as a web HMI on the live VM.

    hmi = load_pages(["st_src/hmi/Main.toml", …], bridge.type_of)   # checked page data
    server = HmiServer(hmi, bridge, port=8080, pose=from_lockstep(transport)).start()
    print(server.url)                                                 # …/?token=… off loopback
    server.stop()

`stvm run FILES --hmi [HOST:]PORT` and `stvm debug … --hmi` do this for the pages listed in the
project's `stvm.toml` (`[hmi] pages = [...]`). The page format is in docs/hmi.md; the web contract
(URLs, `data-var`/`data-action` attributes, `/api/vars`) in `stvm/hmi/server.py`.
"""


__all__ = ["Hmi", "HmiLoadError", "HmiServer", "PoseSource", "from_lockstep", "from_tcp_server", "load_pages"]


# lazy: start-up (the server pulls in starlette and uvicorn; `stvm.hmi.cli` must not)
_HOMES = {"Hmi": "pages", "HmiLoadError": "pages", "load_pages": "pages", "PoseSource": "robot",
          "from_lockstep": "robot", "from_tcp_server": "robot", "HmiServer": "server"}


def __getattr__(name):
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(name)
    import importlib
    return getattr(importlib.import_module(f"stvm.hmi.{home}"), name)
