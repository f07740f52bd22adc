"""The package's layering, as ARCHITECTURE.md draws it: read from the source, not the docs.

- no import cycles between groupwise's modules (imports at module level, outside
  `if TYPE_CHECKING:`; a function may import lazily to keep an extra optional);
- Stable-Baselines3 only under `groupwise.rl`;
- the web server (`groupwise.server`) loads neither RL, the reward model, nor torch: the
  training worker (`groupwise.worker`) is the program that does.
"""

import ast
import subprocess
import sys
from pathlib import Path

import groupwise

ROOT = Path(groupwise.__file__).parent


def _module(path: Path) -> str:
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, modules: set[str] | frozenset[str] = frozenset()) -> set[str]:
    """Modules `path` imports at module level (not under TYPE_CHECKING): `from p import m`
    of a submodule `m` is an import of `p.m`, not of the package `p`."""
    found: set[str] = set()
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = {f"{node.module}.{alias.name}" for alias in node.names}
            found |= (names & modules) or {node.module}
            if names - modules:
                found.add(node.module)
    return found


def _imports_anywhere(path: Path) -> set[str]:
    """Every module `path` imports, at any depth (functions included)."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
    return found


def _graph() -> dict[str, set[str]]:
    modules = {_module(p): p for p in ROOT.rglob("*.py")}
    names = set(modules)
    return {name: _imports(path, names) & names - {name} for name, path in modules.items()}


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return [*stack[stack.index(nxt) :], nxt]
            if nxt not in state and (found := visit(nxt)):
                return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (found := visit(node)):
            return found
    return None


def test_no_import_cycles():
    assert _cycle(_graph()) is None, " → ".join(_cycle(_graph()) or [])


def test_the_cycle_check_finds_a_cycle():
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set()}) is None


def test_stable_baselines3_only_under_rl():
    users = {
        _module(p)
        for p in ROOT.rglob("*.py")
        if "stable_baselines3" in {m.split(".")[0] for m in _imports_anywhere(p)}
    }
    assert users and all(name.startswith("groupwise.rl.") for name in users), users


def test_the_web_server_loads_no_rl_reward_model_or_torch():
    probe = (
        "import sys, groupwise.server.app\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in "
        "('stable_baselines3', 'torch') or m.startswith(('groupwise.rl', 'groupwise.reward', "
        "'groupwise.run.run', 'groupwise.run.round'))))"
    )
    run = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.strip() == "[]"
