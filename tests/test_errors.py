"""Errors name arguments as their reader wrote them: Python names from the library, flags from the command line."""

import ast

import pytest
from paths import EXAMPLE, ROOT

from brdffit import MCMC, BrdfInputError, fit, load_samples
from brdffit.cli import main
from brdffit.cli.arguments import spell
from brdffit.errors import Argument, not_a_choice


def test_a_message_spells_its_arguments_for_each_reader():
    error = BrdfInputError(Argument("burn", "600"), " must be less than ", Argument("steps", "500"))
    assert str(error) == "burn=600 must be less than steps=500"
    assert error.spelled(spell) == "--burn 600 must be less than --steps 500"
    choice = not_a_choice("n_starts", "x", ["1", "2"])
    assert str(choice) == "n_starts='x' is not allowed; choose one of: 1, 2"
    assert choice.spelled(spell) == "--starts 'x' is not allowed; choose one of: 1, 2"


@pytest.fixture(scope="module")
def samples():
    return load_samples(EXAMPLE)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (dict(n_starts=0), "n_starts=0 is not allowed; give a whole number ≥ 1"),
        (dict(max_steps=1.5), "max_steps=1.5 is not allowed"),
        (dict(dtype="float16"), "dtype='float16' is not allowed; choose one of: float64, float32"),
        (dict(max_theta=95), "max_theta=95 is not allowed; give degrees in (0, 90]"),
        (dict(fresnel="schlick"), "fresnel does not apply to model ward; it takes no options"),
        (
            dict(max_step=3),
            "max_step is not an argument of the fit, nor an option of any model"
            " (anisotropic, basis, distribution, fresnel, int_ior, lobes, ridge, shadowing, sheen)",
        ),
        (
            dict(uncertainty="mcmc", mcmc=MCMC(walkers=4)),
            "walkers=4 is too few for 8 sampled parameters; give at least 16",
        ),
    ],
)
def test_the_library_names_python_arguments(samples, call, message):
    with pytest.raises(BrdfInputError) as error:
        fit(samples, "ward", **call)
    assert str(error.value).startswith(message) and "--" not in str(error.value)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--starts", "0"], "--starts 0 is not allowed; give a whole number ≥ 1"),
        (["--max-theta", "95"], "--max-theta 95.0 is not allowed; give degrees in (0, 90]"),
        (
            ["--uncertainty", "mcmc", "--walkers", "4"],
            "--walkers 4 is too few for 8 sampled parameters; give at least 16",
        ),
        (["--model", "lafortune", "--lobes", "9"], "--lobes 9 is not allowed; give a whole number from 1 to 8"),
    ],
)
def test_the_command_line_names_its_flags(argv, message, tmp_path, capsys):
    status = main(["fit", str(EXAMPLE), "-o", str(tmp_path / "r.json"), *argv])
    err = capsys.readouterr().err
    assert status == 2 and err == f"brdffit: error: {message}\n" and not list(tmp_path.iterdir())


def test_no_library_error_is_written_with_a_flag():
    """Outside ``brdffit/cli`` an error's text never names a flag: it would read wrong from Python."""
    found = []
    for path in sorted((ROOT / "brdffit").rglob("*.py")):
        if "cli" in path.relative_to(ROOT / "brdffit").parts:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and getattr(node.func, "id", "") in ("BrdfInputError", "not_allowed"):
                text = " ".join(
                    piece.value
                    for piece in ast.walk(node)
                    if isinstance(piece, ast.Constant) and isinstance(piece.value, str)
                )
                if "--" in text:
                    found.append(f"{path.relative_to(ROOT)}:{node.lineno}: {text[:60]}")
    assert not found, found


def test_a_warning_names_the_callers_line_not_brdffits(tmp_path):
    """A warning raised deep inside brdffit (the CSV reader, two calls down) is attributed to the line that called
    brdffit, as ``warnings.warn``'s stacklevel means it: the user's file and line, which a filter by module matches."""
    import warnings

    from brdffit import InputWarning

    path = tmp_path / "radians.csv"
    path.write_text("theta_i,phi_i,theta_o,phi_o,value\n0.5,0,0.5,3.1,0.2\n0.7,0,0.2,1.0,0.3\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        line = _line_here() + 1
        load_samples(path)
    said = [warning for warning in caught if issubclass(warning.category, InputWarning)]
    assert said and all((warning.filename, warning.lineno) == (__file__, line) for warning in said), [
        (warning.filename, warning.lineno) for warning in said
    ]


def _line_here() -> int:
    import inspect

    return inspect.currentframe().f_back.f_lineno
