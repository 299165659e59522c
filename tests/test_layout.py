"""The layout holds: imports go one way through the layers, no module imports itself round a circle, every folder,
module and the package's top stay within the house's limits, and the README's architecture tree is the tree on disk.

Layers, lowest first: the base modules (errors, checks, files, JAX set-up, compiled programs), ``physics``,
``data``, ``fitting`` (its rooms in order: objective, solver, starts, single, then many and comparison),
``uncertainty``, then ``api`` / ``views`` / ``export`` (and ``data_synth``), then ``cli``; ``brdffit/__init__.py``,
the public face that re-exports names from every layer, above them all. A module may import its own layer and those
below. Every import counts: those inside functions, and those under ``if TYPE_CHECKING:``, which never run but
still tie one module's meaning to another's.
"""

import ast
import graphlib
import re
import subprocess
import sys
from pathlib import Path

import pytest
from paths import ROOT

PACKAGES = ("brdffit",)
#: The layer of each package or module (the longest prefix named here counts); fractions order the rooms of a layer.
LAYERS = {
    "brdffit": 7,  # the public face: names of every layer, loaded on first use
    "brdffit._version": 0,
    "brdffit._jax": 0,
    "brdffit._programs": 0,
    "brdffit._files": 0,
    "brdffit._progress": 0,
    "brdffit.errors": 0,
    "brdffit.checks": 0,
    "brdffit.physics": 1,
    "brdffit.datadriven": 1,  # the basis and the pca model: physics
    "brdffit.data": 2,
    "brdffit.datadriven.build": 2,  # a basis learned from a library of files: data
    "brdffit.fitting": 3,
    "brdffit.fitting.objective": 3.1,
    "brdffit.fitting.solver": 3.2,
    "brdffit.fitting.starts": 3.3,
    "brdffit.fitting.single": 3.4,
    "brdffit.datadriven.fit": 3.4,  # the pca model's fit, which the single fit dispatches to
    "brdffit.fitting.many": 3.5,
    "brdffit.fitting.comparison": 3.5,
    "brdffit.uncertainty": 4,
    "brdffit.api": 5,
    "brdffit.views": 5,
    "brdffit.export": 5,
    "brdffit.svbrdf": 5,  # spatially varying materials: captures fitted texel by texel into maps
    "brdffit.data_synth": 5,  # synthetic measurements: a model evaluated on a geometry, packaged as samples
    "brdffit.cli": 6,
}
#: The house's limits: modules a folder holds, lines a module holds, modules flat in ``brdffit/`` (``__init__``s count).
MAX_FOLDER_MODULES = 15
MAX_MODULE_LINES = 600
MAX_FLAT_MODULES = 8


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


def imports_of(module: str) -> set[str]:
    """The project modules ``module`` imports, type-only ones included (a name imported from a package counts as the
    package, unless it is a submodule)."""
    path = MODULES[module]
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
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
    # Importing a module runs its packages' __init__ first: those that are not this module's own packages (which
    # run before it) are imported too. A package that imports a module that imports the package again is a circle.
    # brdffit's own __init__ imports nothing at run time but the version (every name loads on first use).
    own = _packages(module) | {module, "brdffit"}
    return found | {package for target in found for package in _packages(target) - own if package in MODULES}


def _packages(module: str) -> set[str]:
    """The packages ``module`` sits in (``brdffit.physics.models.ward``: ``brdffit``, …, ``brdffit.physics.models``)."""
    parts = module.split(".")
    return {".".join(parts[:n]) for n in range(1, len(parts))}


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


def test_the_solver_knows_nothing_of_brdfs():
    """Levenberg-Marquardt is tested on NIST's problems on its own: it imports only the base modules."""
    module = "brdffit.fitting.solver.levenberg_marquardt"
    assert all(layer(target) == 0 for target in GRAPH[module]), sorted(GRAPH[module])


def folders() -> dict[Path, list[Path]]:
    """Each folder of the packages with the modules directly in it."""
    found: dict[Path, list[Path]] = {}
    for path in MODULES.values():
        found.setdefault(path.parent, []).append(path)
    return found


@pytest.mark.parametrize("folder", sorted(folders()), ids=lambda folder: str(folder.relative_to(ROOT)))
def test_a_folder_holds_few_modules(folder):
    modules = folders()[folder]
    limit = MAX_FLAT_MODULES if folder == ROOT / "brdffit" else MAX_FOLDER_MODULES
    assert len(modules) <= limit, f"{folder.relative_to(ROOT)} holds {len(modules)} modules (at most {limit})"


@pytest.mark.parametrize("module", sorted(MODULES))
def test_a_module_is_short(module):
    lines = len(MODULES[module].read_text().splitlines())
    assert lines <= MAX_MODULE_LINES, f"{module} has {lines} lines (at most {MAX_MODULE_LINES})"


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
