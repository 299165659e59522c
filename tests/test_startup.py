"""Start-up: no work at import time, and a compilation cache that later runs reuse."""

import ast
import os
import subprocess
import sys

import pytest
from paths import ROOT

import brdffit
from brdffit._programs.cache import CACHE_VARIABLE, default_cache_dir, enable_compilation_cache


def test_import_loads_no_jax():
    code = "import sys, brdffit; brdffit.__version__; assert 'jax' not in sys.modules, 'jax imported'"
    subprocess.run([sys.executable, "-c", code], check=True)


@pytest.mark.parametrize(
    ("argv", "status", "said"),
    [
        (["--help"], 0, "fit a model to samples files"),
        (["--version"], 0, f"brdffit {brdffit.__version__}"),
        ([], 2, "the following arguments are required: COMMAND"),
        (["fitt"], 2, "invalid choice: 'fitt'"),
    ],
)
def test_help_and_version_import_no_jax(argv, status, said):
    """The command line loads a command's module only to run it: the top-level help needs none of them."""
    code = (
        "import sys\n"
        "from brdffit.cli import main\n"
        f"status = main({argv!r})\n"
        f"assert status == {status}, status\n"
        "loaded = [name for name in ('jax', 'numpy', 'brdffit.physics', 'brdffit.fitting') if name in sys.modules]\n"
        "assert not loaded, loaded\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert said in done.stdout + done.stderr


def test_python_dash_m_runs_the_command_line_from_any_folder(tmp_path):
    """``python -m brdffit`` is the ``brdffit`` command (``brdffit/__main__.py``), wherever it is run."""
    environment = os.environ | {"PYTHONPATH": str(ROOT)}
    done = subprocess.run(
        [sys.executable, "-m", "brdffit", "--version"], capture_output=True, text=True, cwd=tmp_path, env=environment
    )
    assert done.returncode == 0 and done.stdout.strip() == f"brdffit {brdffit.__version__}", done.stderr


def test_the_package_declares_its_licence_and_its_types():
    """A wheel carries LICENSE (``license-files``) and ``py.typed`` (package data): built once by hand with ``pip
    wheel .``, its files were ``brdffit/py.typed``, ``brdffit-…dist-info/licenses/LICENSE`` and ``License-Expression:
    MIT``; here, that the declarations and the files they name are there (a build needs the network)."""
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert project["project"]["license"] == "MIT" and project["project"]["license-files"] == ["LICENSE"]
    assert "MIT License" in (ROOT / "LICENSE").read_text()
    assert project["tool"]["setuptools"]["package-data"]["brdffit"] == ["py.typed"]
    assert (ROOT / "brdffit" / "py.typed").is_file()


LAMBERT_RESULT = (
    '{"model": "lambert", "model_options": {}, "channels": ["r", "g", "b"], "params": {"rho_d": [0.2, 0.3, 0.4]},'
    ' "fit": {"loss": "log", "cost": 0, "rmse": 0, "n_samples": 1, "n_steps": 1, "converged": true}}'
)


@pytest.mark.parametrize(
    "argv",
    [
        ["models"],
        ["info", "{example}"],
        ["info", "{tape}", "--quantity", "cosine-weighted-out"],
        ["convert", "{example}", "{tmp}/oak.dat"],
        ["export", "{tmp}/lambert.json", "--to", "mitsuba", "-o", "{tmp}/lambert.xml"],
        ["fit", "--help"],
        ["compare", "--help"],
        ["export", "--help"],
    ],
    ids=lambda argv: " ".join(argv[:2]),
)
def test_commands_that_compute_nothing_import_no_jax(argv, tmp_path):
    """Listing the models, describing or converting a file, an exact Mitsuba export (a mapping of parameters) and
    the commands' help need no JAX (0.4–1 s to import): ``brdffit/_jax/lazy.py``. The cache is turned on as a fit's is
    (``cache.py`` then leaves it to JAX's environment variables)."""
    from paths import EXAMPLE, TAPE

    (tmp_path / "lambert.json").write_text(LAMBERT_RESULT)
    argv = [part.format(example=EXAMPLE, tape=TAPE, tmp=tmp_path) for part in argv]
    code = "\n".join(
        [
            "import sys",
            "from brdffit.cli import main",
            f"status = main({argv!r})",
            "assert status == 0, status",
            "assert 'jax' not in sys.modules, 'jax imported'",
        ]
    )
    environment = {**os.environ, CACHE_VARIABLE: str(tmp_path / "cache")}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=environment)
    assert done.returncode == 0, done.stdout + done.stderr


def test_the_cache_set_before_jax_is_imported_is_jaxs(tmp_path):
    """Turned on before JAX is imported, the cache waits in JAX's environment variables; JAX then uses it."""
    folder = str(tmp_path / "cache")
    code = "\n".join(
        [
            "import sys",
            "from brdffit._programs.cache import enable_compilation_cache",
            f"enable_compilation_cache({folder!r})",
            "assert 'jax' not in sys.modules",
            "import jax",
            f"assert jax.config.jax_compilation_cache_dir == {folder!r}, jax.config.jax_compilation_cache_dir",
            "assert jax.config.jax_persistent_cache_min_compile_time_secs == 0",
        ]
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr


def test_the_lazy_names_and_the_type_checkers_imports_agree():
    """``_EXPORTS`` and ``_MODULES`` (what loads at run time) and the ``TYPE_CHECKING`` block (what IDEs see) list
    the same names, from the same modules."""
    tree = ast.parse((ROOT / "brdffit" / "__init__.py").read_text())
    block = next(node for node in tree.body if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test))
    imported = {
        alias.asname: "." + (node.module or "") + ("" if alias.name == alias.asname else f":{alias.name}")
        for node in block.body
        for alias in node.names
    }
    # from .views import plots; from . import export
    modules = {name: path.rpartition(".")[0] or "." for name, path in brdffit._MODULES.items()}
    assert imported == brdffit._EXPORTS | modules


def test_public_names_resolve_lazily():
    assert set(brdffit.__all__) <= set(dir(brdffit))
    for name in brdffit.__all__:
        assert getattr(brdffit, name) is not None
    try:
        brdffit.no_such_name  # noqa: B018
    except AttributeError as error:
        assert "has no attribute 'no_such_name'" in str(error)


def test_no_submodule_shadows_a_public_name():
    """Importing a submodule binds it as a package attribute; none may be called like a public name
    (``brdffit.fit`` must stay the function however the modules were imported); the public modules
    (``brdffit.plots``) are the exception by design."""
    code = (
        "import importlib, pkgutil, types, brdffit\n"
        "for module in pkgutil.walk_packages(brdffit.__path__, 'brdffit.'):\n"
        "    importlib.import_module(module.name)\n"
        "bad = [n for n in brdffit.__all__ if isinstance(getattr(brdffit, n), types.ModuleType)"
        " and n not in brdffit._MODULES]\n"
        "assert not bad, bad\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_cache_folder_rules(monkeypatch, tmp_path):
    monkeypatch.setenv(CACHE_VARIABLE, str(tmp_path / "here"))
    assert default_cache_dir() == tmp_path / "here"
    monkeypatch.setenv(CACHE_VARIABLE, "")
    assert default_cache_dir() is None and enable_compilation_cache() is None
    monkeypatch.delenv(CACHE_VARIABLE)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert default_cache_dir() == tmp_path / "xdg" / "brdffit" / "jax"
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert enable_compilation_cache(blocker / "below") is None  # cannot be created: fits compile as usual


def test_command_line_fills_and_reuses_the_cache(tmp_path):
    """A first `brdffit fit` stores compiled programs; a second run in a new process finds them."""
    environment = {**os.environ, CACHE_VARIABLE: str(tmp_path / "cache")}
    command = [
        sys.executable,
        str(ROOT / "cli.py"),
        "fit",
        str(ROOT / "examples" / "ward-pickled-oak.csv"),
        "--model",
        "lambert",
    ]
    for run in range(2):
        done = subprocess.run(
            [*command, "-o", str(tmp_path / f"r{run}.json")], env=environment, capture_output=True, text=True
        )
        assert done.returncode == 0, done.stderr
        entries = sorted(os.listdir(tmp_path / "cache"))
        assert entries, "the first run must store compiled programs"
        if run == 0:
            first = entries
    assert entries == first, "the second run compiles nothing new"


def test_export_and_render_are_functions_at_the_top(tmp_path):
    """``brdffit.export(result, to, path)`` writes as ``brdffit export`` does (the package ``brdffit.export`` is also
    that function, so its modules still import as before); ``brdffit.render`` is the sphere's render."""
    import brdffit.export.mitsuba

    result = brdffit.FitResult("lambert", {}, ("r", "g", "b"), {"rho_d": [0.2, 0.3, 0.4]}, "log", 0.0, 0.0, 0, 0, True)
    lines = brdffit.export(result, "mitsuba", tmp_path / "grey.xml")
    assert lines == ["exact"] and 'type="diffuse"' in (tmp_path / "grey.xml").read_text()
    assert callable(brdffit.export) and callable(brdffit.export.mitsuba.mitsuba_bsdf)
    from brdffit.export.mitsuba_render import render_sphere

    assert brdffit.render is render_sphere
