"""stvm: a Structured Text (IEC 61131-3, Omron Sysmac dialect) virtual machine.

    project = stvm.load(["main.st"])          # parse, check, lower (cached)
    vm = project.start(scan="1ms")            # a VM on the virtual clock
    vm.run(cycles=100)
    vm["Main.x"]                              # read (or assign) by path
"""

__version__ = "0.1.0"


def load(paths, settings=None, use_cache=True):
    from stvm.project import load as _load
    return _load(paths, settings, use_cache)   # None: the project's settings (stvm.toml [sysmac])


def __getattr__(name):
    if name in ("LoadError", "Project"):
        import stvm.project as project
        return getattr(project, name)
    if name in ("RuntimeFault", "VM"):
        import stvm.runtime.vm as vm
        return getattr(vm, name)
    raise AttributeError(name)
