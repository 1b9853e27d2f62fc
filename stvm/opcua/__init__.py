"""An OPC UA server on the running VM (`stvm run … --opcua [opc.tcp://HOST:PORT]`), as plant
software (SCADA, MES, historians, UaExpert, pytest acceptance tests) sees an Omron NJ's server.

    from stvm.opcua import OpcUaServer, load_config
    server = OpcUaServer(vm, load_config(project.manifest, project.root, files, "opc.tcp://127.0.0.1:0"))
    url = server.start()          # listening; run the VM in this thread, then server.stop()

`config` reads the `--opcua` URL and the manifest's `[opcua]` table, `datatypes` maps IEC types to
OPC UA built-in types, `nodes` chooses and builds the address space, `server` runs asyncua beside
the scan loop on the front-end bridge. asyncua is imported only when a server is wanted.
"""



def __getattr__(name: str):
    # lazy: start-up (`stvm.opcua.cli` adds `--opcua` to every `stvm run`; the config reader
    # loads when the option is given)
    if name in ("DEFAULT_ENDPOINT", "OpcUaConfig", "OpcUaConfigError", "load_config", "parse_endpoint"):
        from stvm.opcua import config   # lazy: start-up
        return getattr(config, name)
    if name == "OpcUaServer":   # asyncua takes ~0.3 s to import: only when a server starts
        from stvm.opcua.server import OpcUaServer   # lazy: start-up (asyncua)
        return OpcUaServer
    raise AttributeError(name)


__all__ = ["DEFAULT_ENDPOINT", "OpcUaConfig", "OpcUaConfigError", "OpcUaServer", "load_config", "parse_endpoint"]
