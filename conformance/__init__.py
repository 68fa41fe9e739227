"""lsdae: conformance checker for FMUs that implement the fmi-ls-dae layered standard."""
from __future__ import annotations

__version__ = "0.1.0"
