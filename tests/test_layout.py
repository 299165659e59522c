"""The layout holds: imports go one way through the layers, no module imports itself round a circle, and the
README's architecture tree is the tree on disk.

Layers, lowest first: the base modules (errors, checks, files, JAX set-up), ``physics``, ``data``, ``fitting``,
``uncertainty``, then ``api`` / ``views`` / ``export`` (and ``data_synth``), then ``cli``. A module may import
its own layer and those below. Imports under ``if TYPE_CHECKING:`` never run and are not counted; the ones
inside functions are.
"""

import ast
import graphlib
import re
import subprocess
import sys
from pathlib import Path

import pytest
from paths import ROOT

PACKAGES = ("brdffit", "data_synth")
LAYERS = {
    "brdffit": 0,
    "brdffit._version": 0,
    "brdffit._jax": 0,
    "brdffit._arrays": 0,
    "brdffit._files": 0,
    "brdffit.errors": 0,
    "brdffit.checks": 0,
    "brdffit.cache": 0,
    "brdffit.physics": 1,
    "brdffit.data": 2,
    "brdffit.fitting": 3,
    "brdffit.uncertainty": 4,
    "brdffit.api": 5,
    "brdffit.cluster": 5,
    "brdffit.views": 5,
    "brdffit.export": 5,
    "data_synth": 5,
    "brdffit.cli": 6,
}


def module_files() -> dict[str, Path]:
    files = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            files[".".join(parts)] = path
    return files


MODULES = module_files()


def layer(module: str) -> int:
    """The layer of ``module``: that of the longest prefix :data:`LAYERS` names."""
    parts = module.split(".")
    for n in range(len(parts), 0, -1):
        if ".".join(parts[:n]) in LAYERS:
            return LAYERS[".".join(parts[:n])]
    raise AssertionError(f"{module} is in no layer; add it to LAYERS")


def _runtime_nodes(tree: ast.AST):
    """Every node except those under ``if TYPE_CHECKING:``."""
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            yield from (child for statement in node.orelse for child in [statement, *_runtime_nodes(statement)])
            continue
        yield node
        yield from _runtime_nodes(node)


def imports_of(module: str) -> set[str]:
    """The project modules ``module`` imports at run time (a name imported from a package counts as the package,
    unless it is a submodule)."""
    path = MODULES[module]
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = set()
    for node in _runtime_nodes(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module
            targets = [
                f"{source}.{alias.name}" if f"{source}.{alias.name}" in MODULES else source for alias in node.names
            ]
        else:
            continue
        for target in targets:
            while target and target not in MODULES:
                target = target.rpartition(".")[0]
            if target and target != module:
                found.add(target)
    return found


GRAPH = {module: imports_of(module) for module in MODULES}


@pytest.mark.parametrize("module", sorted(MODULES))
def test_imports_go_one_way(module):
    upward = sorted(target for target in GRAPH[module] if layer(target) > layer(module))
    assert not upward, f"{module} (layer {layer(module)}) imports a higher layer: {upward}"


def test_no_import_circle():
    try:
        order = list(graphlib.TopologicalSorter(GRAPH).static_order())
    except graphlib.CycleError as error:
        pytest.fail(f"an import circle: {' → '.join(error.args[1])}")
    assert set(order) == set(MODULES)


def test_every_module_imports_in_a_fresh_interpreter_in_layer_order():
    """Lowest layers first, each module alone: a circle that only shows at run time would fail here."""
    ordered = sorted(MODULES, key=lambda module: (layer(module), module))
    code = f"import importlib\nfor name in {ordered!r}:\n    importlib.import_module(name)\n"
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


def readme_tree() -> set[str]:
    """The files and folders under ``brdffit/`` that the README's architecture block names, as relative paths."""
    text = (ROOT / "README.md").read_text()
    block = re.search(r"## Architecture\n.*?```\n(brdffit/\n.*?)```", text, re.S)
    assert block, "the README's architecture section has no tree starting with brdffit/"
    listed, stack = set(), []
    for line in block.group(1).splitlines()[1:]:
        if not line.startswith("  ") or not line.strip():
            break  # the end of brdffit/'s subtree
        depth = (len(line) - len(line.lstrip(" "))) // 2 - 1
        name = line.split()[0]
        stack = [*stack[:depth], name.rstrip("/")]
        listed.add("/".join(stack) + ("/" if name.endswith("/") else ""))
    return listed


def test_readme_architecture_tree_matches_the_files():
    listed = readme_tree()
    package = ROOT / "brdffit"
    on_disk = {str(path.relative_to(package)) for path in package.rglob("*.py")}
    on_disk |= {str(path.relative_to(package)) + "/" for path in package.rglob("*") if path.is_dir()}
    on_disk = {name for name in on_disk if "__pycache__" not in name}
    assert sorted(listed - on_disk) == [], "the README names files that do not exist"
    assert sorted(on_disk - listed) == [], "files the README's architecture tree does not name"
