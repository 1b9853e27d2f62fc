"""stvm: a Structured Text (IEC 61131-3, Omron Sysmac dialect) virtual machine.

    project = stvm.load(["main.st"])          # parse, check, lower (cached)
    vm = project.start(scan="1ms")            # a VM on the virtual clock
    vm.run(cycles=100)
    vm["Main.x"]                              # read (or assign) by path
"""

from stvm.version import __version__  # noqa: F401 (API)

# The API below is imported on first use (start-up time: `import stvm.syntax` must not load the
# project driver, the VM and the stdlib).


def load(paths, settings=None, use_cache=True):
    from stvm.project import load as _load   # lazy: start-up (`import stvm.syntax` must not load the driver and the VM)
    return _load(paths, settings, use_cache)   # None: the project's settings (stvm.toml [sysmac])


def __getattr__(name):
    if name in ("LoadError", "Project"):
        import stvm.project as project   # lazy: start-up (`import stvm.syntax` must not load the driver and the VM)
        return getattr(project, name)
    if name in ("RuntimeFault", "VM"):
        import stvm.runtime.vm as vm   # lazy: start-up (`import stvm.syntax` must not load the driver and the VM)
        return getattr(vm, name)
    raise AttributeError(name)
