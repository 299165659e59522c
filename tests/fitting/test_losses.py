"""Loss residuals (docs/losses.md) and how sigma and weight scale them."""

import math

import jax.numpy as jnp
import numpy as np
import pytest

from brdffit import BrdfInputError
from brdffit.fitting.objective.losses import LOSSES, RELATIVE_FLOOR, get_loss, residual_scale

F, Y, CI = 0.7, 0.5, math.cos(math.radians(60))
BY_HAND = {
    "log": math.log(1 + F * CI) - math.log(1 + Y * CI),
    "l2": F - Y,
    "cosine": (F - Y) * CI,
    "cbrt": F ** (1 / 3) - Y ** (1 / 3),
    "relative": (F - Y) / Y,
}


@pytest.mark.parametrize("name", list(LOSSES))
def test_residual_formulas(name):
    loss = get_loss(name)
    residual = loss.transform(jnp.asarray(F), Y, CI) - loss.transform(jnp.asarray(Y), Y, CI)
    assert float(residual) == pytest.approx(BY_HAND[name], rel=1e-14)


def test_relative_floor():
    loss = get_loss("relative")
    assert float(loss.transform(jnp.asarray(1e-3), 0.0, 1.0)) == pytest.approx(1e-3 / RELATIVE_FLOOR)


@pytest.mark.parametrize("name", list(LOSSES))
def test_sigma_makes_every_loss_chi_squared_to_first_order(name):
    """With sigma, residual ≈ (f - y)/sigma for f near y, whatever the loss (the slope is taken at y)."""
    loss = get_loss(name)
    y = np.array([[0.5]])
    sigma = np.array([[0.01]])
    scale = np.asarray(residual_scale(loss, y, np.array([[CI]]), sigma=sigma))
    f = 0.5 + 1e-6
    residual = (
        float(loss.transform(jnp.asarray(f), y[0, 0], CI)) - float(loss.transform(jnp.asarray(0.5), y[0, 0], CI))
    ) * scale[0, 0]
    assert residual == pytest.approx(1e-6 / 0.01, rel=1e-5)


def test_l2_scale_is_sqrt_weight_over_sigma():
    loss = get_loss("l2")
    scale = residual_scale(
        loss, np.array([[0.2, 0.3]]), np.array([[0.5]]), sigma=np.array([[0.01, 0.02]]), weight=np.array([4.0])
    )
    np.testing.assert_allclose(scale, [[2 / 0.01, 2 / 0.02]])


def test_unknown_loss():
    with pytest.raises(
        BrdfInputError, match=r"^loss='l1' is not a loss; choose one of: log, l2, cosine, cbrt, relative$"
    ):
        get_loss("l1")
