"""Helpers of the tests of research/'s scripts (they are files, not a package)."""

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

RESEARCH = Path(__file__).parents[2] / "research"


def research_script(name: str) -> ModuleType:
    """research/`name`.py imported as the module `name`."""
    spec = importlib.util.spec_from_file_location(name, RESEARCH / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses resolve their module by name
    spec.loader.exec_module(module)
    return module
