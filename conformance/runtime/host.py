"""This machine as the FMI standard names it: the platform tuple and the library extension."""
from __future__ import annotations

import platform
import sys


def host_platform_tuple() -> str:
    """The FMI 3 platform tuple of this machine, e.g. ``x86_64-linux``."""
    machine = platform.machine().lower()
    arch = {"amd64": "x86_64", "arm64": "aarch64", "i386": "x86", "i686": "x86",
            "armv7l": "aarch32"}.get(machine, machine)
    system = ("linux" if sys.platform.startswith("linux") else "darwin"
              if sys.platform == "darwin" else "windows" if sys.platform in ("win32", "cygwin")
              else sys.platform)
    return f"{arch}-{system}"


def library_extension() -> str:
    return {"darwin": ".dylib", "win32": ".dll", "cygwin": ".dll"}.get(sys.platform, ".so")
