"""Every core module imports without the `app` and `study` extras (pyproject.toml), as after
a plain `pip install groupwise`: the extras' packages are hidden from a fresh interpreter.
(`scripts/check-install.sh` checks the same in a real venv; this runs with `make test`.)"""

import subprocess
import sys

SCRIPT = """
import importlib, importlib.abc, pkgutil, sys

HIDDEN = {"fastapi", "uvicorn", "sqlalchemy", "pyarrow", "matplotlib", "sklearn", "ray"}

class Hide(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in HIDDEN:
            raise ModuleNotFoundError(f"No module named {name!r} (hidden: an extra)")
        return None

sys.meta_path.insert(0, Hide())
import groupwise
extras = ("groupwise.server", "groupwise.storage", "groupwise.worker", "groupwise.study")
names = [m.name for m in pkgutil.walk_packages(groupwise.__path__, "groupwise.")]
core = [n for n in names if not n.startswith(extras)]
for name in core:
    importlib.import_module(name)
print(len(core))
"""


def test_core_modules_import_without_the_extras():
    run = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    assert int(run.stdout.strip()) > 40
