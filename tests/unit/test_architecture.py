"""The package's layering, as ARCHITECTURE.md draws it: read from the source, not the docs.

- every import of every module (at module level or inside a function; only imports under
  `if TYPE_CHECKING:` are left out) points to its own layer of `LAYERS` or a lower one;
- no import cycles between groupwise's modules, function-level imports included;
- Stable-Baselines3 only under `groupwise.rl`;
- the web server (`groupwise.server`) loads neither RL, the reward model, nor torch: the
  training worker (`groupwise.worker`) is the program that does.
"""

import ast
import shutil
import subprocess
import sys
from pathlib import Path

import groupwise

ROOT = Path(groupwise.__file__).parent

LAYERS: list[set[str]] = [
    # leaves: the data types every layer shares (the package's own API loads lazily)
    {"groupwise", "groupwise.types", "groupwise.episodes"},
    {"groupwise.envs", "groupwise.preferences", "groupwise.config_history"},
    {"groupwise.config", "groupwise.recipes", "groupwise.agent_file"},
    # the core's computations: no SB3, FastAPI or matplotlib
    {"groupwise.behaviour", "groupwise.clips", "groupwise.reward"},
    # the app's database: below everything RL, so the server can load it without them
    {"groupwise.storage"},
    {"groupwise.query"},
    {"groupwise.teachers", "groupwise.rl"},
    {"groupwise.pool"},
    {"groupwise.run"},
    # the programs around the loop
    {"groupwise.study"},
    {"groupwise.worker"},
    {"groupwise.server"},
    {"groupwise.commands", "groupwise.cli"},
]
"""Lowest first; a module belongs to the longest entry that is it or a package above it."""


def _module(path: Path, root: Path = ROOT) -> str:
    parts = path.relative_to(root.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _is_type_checking(node: ast.AST) -> bool:
    return isinstance(node, ast.If) and ast.unparse(node.test) in (
        "TYPE_CHECKING",
        "typing.TYPE_CHECKING",
    )


def _import_nodes(tree: ast.AST) -> list[ast.Import | ast.ImportFrom]:
    """Every import statement at any depth (functions, classes, `try`), except those under
    `if TYPE_CHECKING:` (their `else:` branch counts)."""
    found: list[ast.Import | ast.ImportFrom] = []
    for child in ast.iter_child_nodes(tree):
        if isinstance(child, ast.Import | ast.ImportFrom):
            found.append(child)
        elif _is_type_checking(child):
            assert isinstance(child, ast.If)
            for node in child.orelse:
                found += _import_nodes(ast.Module(body=[node], type_ignores=[]))
        else:
            found += _import_nodes(child)
    return found


def _imports(path: Path, modules: set[str] | frozenset[str] = frozenset()) -> set[str]:
    """Modules `path` imports anywhere in it: `from p import m` of a submodule `m` is an
    import of `p.m`, not of the package `p` (unless it also imports names defined in `p`)."""
    found: set[str] = set()
    for node in _import_nodes(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif node.module and node.level == 0:
            names = {f"{node.module}.{alias.name}" for alias in node.names}
            found |= (names & modules) or {node.module}
            if names - modules:
                found.add(node.module)
    return found


def _graph(root: Path = ROOT) -> dict[str, set[str]]:
    """groupwise module → the groupwise modules it imports (itself left out)."""
    paths = {_module(p, root): p for p in root.rglob("*.py")}
    names = set(paths)
    return {name: (_imports(path, names) & names) - {name} for name, path in paths.items()}


def _layer(module: str) -> int | None:
    """The index in `LAYERS` of the longest entry that is `module` or a package above it."""
    best: tuple[int, int] | None = None
    for index, layer in enumerate(LAYERS):
        for entry in layer:
            if (module == entry or module.startswith(entry + ".")) and (
                best is None or len(entry) > best[0]
            ):
                best = (len(entry), index)
    return None if best is None else best[1]


def _upward(graph: dict[str, set[str]]) -> list[str]:
    """Imports of a higher layer than the importer's, as "importer (layer) → imported (layer)"."""
    found = []
    for importer, targets in sorted(graph.items()):
        for imported in sorted(targets):
            low, high = _layer(importer), _layer(imported)
            if low is not None and high is not None and high > low:
                found.append(f"{importer} ({low}) → {imported} ({high})")
    return found


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
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


def _violations(root: Path = ROOT) -> list[str]:
    """Everything the layering forbids in the package at `root`, in words; [] when none."""
    graph = _graph(root)
    found = [f"{m} is in no layer" for m in sorted(graph) if _layer(m) is None]
    found += [f"upward import: {edge}" for edge in _upward(graph)]
    cycle = _cycle(graph)
    if cycle:
        found.append("import cycle: " + " → ".join(cycle))
    return found


def test_every_import_points_down_the_layers_and_none_forms_a_cycle():
    assert _violations() == []


def _copy(tmp_path: Path) -> Path:
    root = tmp_path / "groupwise"
    shutil.copytree(ROOT, root, ignore=shutil.ignore_patterns("__pycache__", "static"))
    return root


def _plant(path: Path, line: str) -> None:
    path.write_text(path.read_text() + f"\n\ndef _planted():\n    {line}\n")


def test_the_checker_finds_an_upward_import_inside_a_function(tmp_path):
    root = _copy(tmp_path)
    assert _violations(root) == []
    _plant(root / "episodes" / "fragments.py", "from groupwise.run.run import Run  # noqa")
    upward, *others = _violations(root)
    assert upward == "upward import: groupwise.episodes.fragments (0) → groupwise.run.run (8)"
    assert all(found.startswith("import cycle: ") for found in others)  # run imports episodes


def test_the_checker_finds_a_cycle_within_a_layer(tmp_path):
    root = _copy(tmp_path)
    _plant(root / "behaviour" / "linkage.py", "import groupwise.behaviour.tree  # noqa")
    (found,) = _violations(root)
    assert found.startswith("import cycle: ")
    assert {"groupwise.behaviour.linkage", "groupwise.behaviour.tree"} <= set(
        found.removeprefix("import cycle: ").split(" → ")
    )


def test_an_import_under_type_checking_is_left_out(tmp_path):
    root = _copy(tmp_path)
    path = root / "episodes" / "ids.py"
    path.write_text(
        "from typing import TYPE_CHECKING\n\nif TYPE_CHECKING:\n    import groupwise.run.run\n"
        + path.read_text()
    )
    assert _violations(root) == []


def test_the_layer_of_a_module_is_its_longest_entry():
    assert _layer("groupwise") == 0
    assert _layer("groupwise.episodes.ids") == 0
    assert _layer("groupwise.rl.ppo") == _layer("groupwise.teachers")
    assert _layer("groupwise.server.routes.agent") == len(LAYERS) - 2
    assert _layer("elsewhere.module") is None


def test_stable_baselines3_only_under_rl():
    users = {
        _module(p)
        for p in ROOT.rglob("*.py")
        if "stable_baselines3" in {m.split(".")[0] for m in _imports(p)}
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
