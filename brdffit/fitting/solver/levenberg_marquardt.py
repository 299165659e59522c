"""Levenberg-Marquardt after MINPACK's ``lmder``, as an optimistix least-squares solver, for any residuals.

:func:`least_squares` solves ``min_y |fn(y, args)|²`` for a vector ``y`` by ``optimistix.least_squares`` with
:class:`ScaledLevenbergMarquardt`, and ``fn`` is the true residual function: optimistix traces it for the residuals'
shape, the solver differentiates it (or takes an equivalent pass, below), and optimistix's ``ImplicitAdjoint``
differentiates the solution through it. Nothing here knows about BRDFs; the BRDF fit (``compiled.py``), the data-driven
fit (``datadriven/fit.py``), the glTF export (``export/gltf.py``) and the NIST StRD tests
(``tests/fitting/test_nist.py``) all call :func:`least_squares`.

**What is optimistix's, through its public API.** The iterative loop, ``max_steps`` and the result codes
(``optx.least_squares``, ``optx.RESULTS``); the solver, descent and search interfaces
(``optx.AbstractLeastSquaresSolver``, ``optx.AbstractDescent``, ``optx.AbstractSearch``,
``optx.FunctionInfo.EvalGradHessian``); and derivatives of the solution with respect to ``args``:
``optx.ImplicitAdjoint`` applies the implicit function theorem to ``∇½|fn|² = 0`` at the solution (Blondel et
al., "Efficient and modular implicit differentiation", NeurIPS 2022), never to the solver's iterations, with
lineax's SVD solve (``lx.SVD``) so that a direction the residuals do not determine (a held parameter, an
albedo at 0: a zero row of the Hessian) gets the pseudo-inverse's zero derivative instead of a NaN.

**What is owned here, and why** (Moré, "The Levenberg-Marquardt algorithm: implementation and theory", 1978;
MINPACK's ``lmder``). optimistix's ``LevenbergMarquardt`` cannot be configured into these:

* **The descent** (:class:`ScaledTrustRegionDescent`): the step lives in Marquardt's scaled variables
  ``z = D δ`` (``D² = diag JᵀJ``, Marquardt 1963), of length at most a trust radius.
  optimistix damps with ``λ I`` (Levenberg 1944), which is not invariant to a parameter's scale: a column that
  vanishes (a log-albedo whose albedo tends to 0) gets a vanishing step and crawls for hundreds of steps.
* **The trust-region update**, one of two, as the descent's ``absolute_radius`` says:

  - MINPACK's (:class:`MinpackTrustRegion`, :data:`MINPACK_DESCENT`, the default): the radius is a length in
    the scaled variables kept from step to step, ``factor·|D y0|`` at first, and each ratio test sets it from
    the length of the step just tried, so it never stays far beyond the steps the model asks for. optimistix's
    ``ClassicalTrustRegion`` keeps a radius in unscaled variables and moves it by constant factors alone.
  - The BRDF fits' (:class:`CappedTrustRegion`, ``solver/compiled.py``'s ``fit_descent()``, the glTF export's
    descent): the radius is a fraction of each point's Gauss-Newton step, grown and shrunk with MINPACK's
    thresholds as optimistix's ``ClassicalTrustRegion`` would, but held at 1 (the Gauss-Newton step), where
    optimistix's lets it grow without bound and a step size beyond the Gauss-Newton step only costs rejections
    to come back. optimistix's state is private, so the update is owned here.

  They differ where a far start needs a bounded first step or a radius carried across points: on NIST's
  certified problems (``tests/fitting/test_nist.py``) MINPACK's solves all 54 cases in 3,417 steps, where the
  fraction ends elsewhere on BoxBOD and MGH10 from the far start and takes 15,309 (10,773 on MGH17 alone). The
  BRDF fits keep the fraction: their guards, starts and step counts (pinned against MINPACK by
  ``tests/fitting/test_solver.py``) were measured with it, and MINPACK's radius has not been measured on them.
* **The stopping tests**: MINPACK's ``ftol`` (relative reduction of the sum of squares, actual and predicted),
  ``gtol`` (cosine between the residuals and every Jacobian column) and an exact fit (``|r| ≤ atol``), where
  optimistix's Cauchy test asks every parameter step and residual change to be small, which a parameter heading
  to a bound (an albedo to 0 in log space) never passes.
* **The normal equations** ``rᵀr``, ``Jᵀr``, ``JᵀJ`` are what a step needs. By default they come from ``fn``
  (``jax.jacfwd``); a caller may pass ``normal_equations``, a faster pass giving the same sums (the BRDF fit
  accumulates them chunk by chunk without forming the Jacobian, so memory does not grow with the data), which
  the tests check against ``fn``'s Jacobian.
* **A step budget** (``budget``): a ``max_steps`` that a compiled program takes as an argument.
"""

from collections.abc import Callable
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import lineax as lx
import optimistix as optx
from optimistix import RESULTS

#: How the solution is differentiated: the implicit function theorem, with the pseudo-inverse of the Hessian of
#: ``½|r|²`` (lineax's SVD solve), so that directions the residuals do not determine get no derivative.
ADJOINT = optx.ImplicitAdjoint(linear_solver=lx.SVD())


class _DescentState(eqx.Module):
    live: Any  # (k,) bool: columns of J that can change the residuals
    scale: Any  # D, (k,): the running scale on live columns, 1 on dead ones
    largest_norms: Any  # the largest sqrt(diag JᵀJ) of each column so far, (k,)
    eigenvalues: Any  # σ of D⁻¹JᵀJD⁻¹, (k,)
    eigenvectors: Any  # V, (k, k)
    projected: Any  # c = Vᵀ D⁻¹ Jᵀr, (k,)
    newton_norm: Any  # |z_GN| = |c / σ|


class ScaledTrustRegionDescent(optx.AbstractDescent):
    """Levenberg-Marquardt step in Marquardt's scaled variables, inside a trust radius.

    In ``z = D δ`` (``D² = diag JᵀJ``, Marquardt 1963) the step is
    ``z(λ) = -(D⁻¹JᵀJD⁻¹ + λ I)⁻¹ D⁻¹Jᵀr``: the Gauss-Newton step ``z(0)`` when it lies within the radius ``Δ``,
    else the ``λ`` with ``|z(λ)| = Δ`` (Moré 1978's trust-region form; optimistix's
    ``IndirectDampedNewtonDescent`` makes the same choice of scale), found from the eigen-decomposition of the
    k×k scaled matrix, where ``|z(λ)|² = Σ cᵢ² / (σᵢ + λ)²`` is monotone in ``λ``, by bisection in ``log λ``.
    So each rejection shortens the step by the trust region's factor, where damping ``λ I`` from a small ``λ``
    barely shortens it.

    What the step size ``s`` the search hands over means is this descent's choice:

    * ``absolute_radius=False`` (the default, the BRDF fits'): a fraction of the Gauss-Newton step,
      ``Δ = min(s, 1)·|z(0)|``, updated by :class:`CappedTrustRegion`.
    * ``absolute_radius=True`` (MINPACK's, :data:`MINPACK_DESCENT`): the radius itself, ``Δ = s``, a length in
      the scaled variables that :class:`MinpackTrustRegion` keeps from step to step (``lmder``'s ``delta``; the
      ``λ`` is ``lmpar``'s, found exactly here where ``lmpar`` stops within 10% of ``Δ``).

    A column of ``J`` that is 0 (a held parameter) is *dead*: it is left out of the step (and of the cosine
    test), where it would make the scaled matrix singular. Three options, each off in MINPACK and so by default,
    suit coordinates that are logarithms or logits (the BRDF fit's, ``compiled.fit_descent``):

    * ``drop_negligible_columns``: a column whose squared norm is below ``ε·max`` (an albedo that has gone to 0
      in log space) is dead too: it cannot change the residuals at float precision over a step of order 1, and
      its length would otherwise take all of the step and leave the other parameters a vanishing radius. In
      units of any scale it is wrong: NIST's Hahn1 has columns 10⁹ apart (``1`` and ``x³``) and stops 10
      digits short with it (``tests/fitting/test_nist.py``).
    * ``max_coordinate_step``: no coordinate moves by more than this in one step (the whole step is shortened
      along its direction), an absolute length.
    * ``running_scale=False``: the scale is each column's norm now, not MINPACK's (``lmder``, mode 1) largest norm
      so far. MINPACK's keeps the step of a column that shrinks on the way (an albedo heading to 0) the size it
      had, instead of a step that grows as it shrinks.

    The last two are guards against a fit that runs off into a flat region (MINPACK's scale on, the step
    bounded): without them, brdffit's grid starts ended in a false optimum on 2 of 300 small Ward fits and 3 of
    200 Cook-Torrance ones (an albedo collapsed to 3e-10, a Fresnel f0 saturated at 1) that MINPACK from the same
    starts did not; with them, none. The glTF fit (``export/gltf.py``), whose logistic coordinates must travel
    far to saturate a colour at 0 or 1, turns both off.
    """

    drop_negligible_columns: bool = False
    max_coordinate_step: float | None = None
    running_scale: bool = True
    absolute_radius: bool = False

    def init(self, y, f_info_struct):
        k = y.size
        zeros = jnp.zeros(k, y.dtype)
        live = jnp.ones(k, bool)
        return _DescentState(live, zeros, zeros, zeros, jnp.zeros((k, k), y.dtype), zeros, jnp.zeros((), y.dtype))

    def query(self, y, f_info, state):
        gram, gradient = f_info.hessian.as_matrix(), f_info.grad
        tiny = jnp.finfo(gram.dtype).tiny
        eps = jnp.finfo(gram.dtype).eps
        diagonal = jnp.diag(gram)
        live = diagonal > (eps * jnp.max(diagonal) if self.drop_negligible_columns else 0.0)
        norms = jnp.sqrt(diagonal)
        running = jnp.maximum(state.largest_norms, norms) if self.running_scale else norms
        scale = jnp.where(live, running, 1.0)
        # Dead columns become an identity block with no gradient: no step and no length there.
        live_pair = live[:, None] & live[None, :]
        scaled = jnp.where(live_pair, gram / scale[:, None] / scale[None, :], jnp.eye(gram.shape[0], dtype=gram.dtype))
        eigenvalues, eigenvectors = jnp.linalg.eigh(scaled)
        # Directions J cannot see get the curvature eps·σ_max: finite, and long enough that the radius decides.
        eigenvalues = jnp.maximum(eigenvalues, eps * jnp.max(eigenvalues) + tiny)
        projected = eigenvectors.T @ jnp.where(live, gradient / scale, 0.0)
        newton_norm = jnp.sqrt(jnp.sum((projected / eigenvalues) ** 2))
        return _DescentState(live, scale, running, eigenvalues, eigenvectors, projected, newton_norm)

    def step(self, step_size, state):
        sigma, c = state.eigenvalues, state.projected
        if self.absolute_radius:
            radius = step_size
            newton = state.newton_norm <= radius
        else:
            radius = jnp.minimum(step_size, 1.0) * state.newton_norm
            newton = step_size >= 1.0

        def length(log_lambda):
            return jnp.sqrt(jnp.sum((c / (sigma + jnp.exp(log_lambda))) ** 2))

        # |z(λ)| ≤ |c|/λ, so at λ_hi = |c|/radius the step is inside the radius; at λ_hi·1e-20 it is not.
        high = jnp.log(jnp.sqrt(jnp.sum(c * c)) / jnp.maximum(radius, jnp.finfo(c.dtype).tiny))
        low = high - 46.0

        def bisect(_, bounds):
            lo, hi = bounds
            middle = 0.5 * (lo + hi)
            outside = length(middle) > radius
            return jnp.where(outside, middle, lo), jnp.where(outside, hi, middle)

        _, log_lambda = jax.lax.fori_loop(0, 60, bisect, (low, high))
        damping = jnp.where(newton, 0.0, jnp.exp(log_lambda))
        z = -state.eigenvectors @ (c / (sigma + damping))
        delta = jnp.where(state.live, z / state.scale, 0.0)
        if self.max_coordinate_step is not None:
            largest = jnp.max(jnp.abs(delta))
            delta = delta * jnp.minimum(1.0, self.max_coordinate_step / jnp.where(largest > 0, largest, 1.0))
        finite = jnp.all(jnp.isfinite(delta))
        return jnp.where(finite, delta, 0.0), RESULTS.where(finite, RESULTS.successful, RESULTS.singular)


#: The default descent: MINPACK's scale (each column's largest norm so far) and radius (an absolute length in the
#: scaled variables, :class:`MinpackTrustRegion`), no column dropped, no step bounded.
MINPACK_DESCENT = ScaledTrustRegionDescent(absolute_radius=True)


def predicted_reduction(y_diff, f_info):
    """The quadratic model's change of ``½|r|²`` for the step ``y_diff``: ``gᵀδ + ½ δᵀ(JᵀJ)δ`` (negative for a
    descent), ``g = Jᵀr`` and ``JᵀJ`` from ``f_info``. Where the step is Levenberg-Marquardt's with damping ``λ``
    it equals ``−½(|Jδ|² + 2λ|Dδ|²)``, ``−prered·½|r|²`` with ``lmder``'s ``prered`` (relative to ``|r|²``)."""
    curvature = jnp.matmul(f_info.hessian.as_matrix(), y_diff, precision=jax.lax.Precision.HIGHEST)
    return jnp.dot(y_diff, f_info.grad + 0.5 * curvature, precision=jax.lax.Precision.HIGHEST)


class _SearchState(eqx.Module):
    step_size: Any  # the fraction of the Gauss-Newton step the next trial takes, in (0, 1]


class CappedTrustRegion(optx.AbstractSearch):
    """A trust-region update on the ratio ``ρ`` of the actual to the predicted reduction of ``½|r|²``, with
    MINPACK's thresholds, whose step size never exceeds the Gauss-Newton step.

    Accept the step tried when ``ρ ≥ accept`` (1e-4, MINPACK's); then multiply the step size by ``grow`` (4) when
    ``ρ > good`` (0.75, MINPACK's), else keep it; reject it and multiply the step size by ``shrink`` (0.25) when
    ``ρ < accept``. The step size is a fraction of the Gauss-Newton step (:class:`ScaledTrustRegionDescent`) and
    never exceeds 1: beyond it the descent takes the Gauss-Newton step anyway, and a larger radius would only
    need rejections to come back (MINPACK bounds its radius by the length of the step taken, ``lmpar``).

    These are the decisions of optimistix's ``ClassicalTrustRegion(low_cutoff=1e-4, high_cutoff=0.75,
    high_constant=4, low_constant=0.25)`` (whose defaults, 0.01 and 0.99, rarely enlarge the region, and the fit
    crawls), computed the same way (the predicted reduction is the quadratic model's ``gᵀδ + ½δᵀGδ``), with the
    cap at 1 added: optimistix's state is private, so the whole update is owned here.
    """

    accept: float = 1e-4
    good: float = 0.75
    grow: float = 4.0
    shrink: float = 0.25

    def init(self, y, f_info_struct):
        return _SearchState(step_size=jnp.array(1.0))

    def predict_reduction(self, y_diff, f_info):
        """:func:`predicted_reduction`."""
        return predicted_reduction(y_diff, f_info)

    def step(self, first_step, y, y_eval, f_info, f_eval_info, state):
        predicted = self.predict_reduction(y_eval - y, f_info)
        # ρ ≥ c  ⇔  actual ≤ c·predicted, both reductions negative for a descent: no division.
        actual = f_eval_info.f - f_info.f
        accept = (actual <= self.accept * predicted) | first_step
        good = (actual < self.good * predicted) & (predicted < 0) & ~first_step
        factor = jnp.where(accept, jnp.where(good, self.grow, 1.0), self.shrink)
        step_size = jnp.minimum(factor * state.step_size, 1.0)
        return step_size, accept, RESULTS.successful, _SearchState(step_size)


def _minpack_scale(largest_norms, gram):
    """MINPACK's scale (``lmder``, mode 1) from the largest column norms so far and ``JᵀJ`` at the point now: the
    new largest norms and ``D``, each column's largest norm so far, 1 where the column is 0 now (as the descent's
    with ``running_scale``; a column left out as dead gets no step, so its scale does not matter)."""
    norms = jnp.sqrt(jnp.diag(gram))
    largest = jnp.maximum(largest_norms, norms)
    return largest, jnp.where(norms > 0, largest, 1.0)


class _RadiusState(eqx.Module):
    radius: Any  # Δ, the scaled length |D δ| the next trial may take
    largest_norms: Any  # each column's largest norm so far, (k,)
    scale: Any  # D with which the step in flight was computed, (k,): its scaled length is measured with it
    tried: Any  # whether a step has been tried: MINPACK clips the first Δ to the first step's length


class MinpackTrustRegion(optx.AbstractSearch):
    """MINPACK's trust-region update (``lmder``; Moré 1978, section 7): the radius ``Δ`` is an absolute length
    in the scaled variables ``z = D δ``, kept from step to step and updated from the ratio ``ρ`` of the actual to
    the predicted reduction of ``|r|²`` and the scaled length ``|D δ|`` of the step tried. It goes with
    :class:`ScaledTrustRegionDescent` ``(absolute_radius=True)``, whose step is the ``λ`` with ``|D δ| = Δ``.

    * At the start, ``Δ = factor·|D y0|`` (``factor`` where ``D y0 = 0``), clipped to the length of the first
      step tried (the Gauss-Newton step, if shorter).
    * ``ρ ≤ ¼`` (or no reduction predicted, or ``|r|²`` not finite): ``Δ ← t·min(Δ, 10|D δ|)``, with ``t = ½``
      when ``|r|`` did not grow, else the minimiser of the parabola through ``f(0)``, ``f'(0) = gᵀδ`` and
      ``f(1)``, ``t = ½ gᵀδ / (gᵀδ − Δf)`` (``f = ½|r|²`` along the step, ``g = Jᵀr``), and ``t = 1/10`` where that
      is less or where ``|r|`` grew tenfold.
    * ``ρ ≥ ¾``, or the radius did not bind (the step was Gauss-Newton's, MINPACK's ``par = 0``):
      ``Δ ← 2|D δ|``. So the radius never stays far beyond the steps the model asks for.
    * Otherwise ``Δ`` is kept. As in :class:`CappedTrustRegion`, the step is accepted when ``ρ ≥ 1e-4``.

    ``factor`` is MINPACK's (``lmder``'s argument, which MINPACK advises between 0.1 and 100, 100 "generally").
    The default here is 1, a first step no longer than the start itself in the scaled variables: with 100,
    NIST's BoxBOD from its start 1 takes a first Gauss-Newton step that sends ``b2`` from 1 to ~88, where its
    column vanishes, in MINPACK (scipy's ``leastsq``) as here; with 1 both solve all 54 of NIST's cases, in
    fewer evaluations (MINPACK 2,869 against 3,693, here 3,417 against 4,277; ``tests/fitting/test_nist.py``).

    The ``D`` that measures the step is MINPACK's running one (:func:`_minpack_scale`), kept in this search's
    state because a search sees the function's sums, not the descent's state: the descent must use it too
    (``running_scale=True``, checked by :class:`ScaledLevenbergMarquardt`). optimistix's ``ClassicalTrustRegion``
    keeps an absolute radius too, but in unscaled variables and updated by constant factors, without the step's
    length.
    """

    factor: float = 1.0
    accept: float = 1e-4
    poor: float = 0.25
    good: float = 0.75

    def init(self, y, f_info_struct):
        k = y.size
        zeros = jnp.zeros(k, y.dtype)
        return _RadiusState(jnp.zeros((), y.dtype), zeros, jnp.ones(k, y.dtype), jnp.array(False))

    def predict_reduction(self, y_diff, f_info):
        """:func:`predicted_reduction`."""
        return predicted_reduction(y_diff, f_info)

    def step(self, first_step, y, y_eval, f_info, f_eval_info, state):
        y_diff = y_eval - y
        predicted = predicted_reduction(y_diff, f_info)
        actual = f_eval_info.f - f_info.f
        # ρ ≥ c  ⇔  actual ≤ c·predicted, both reductions negative for a descent: no division. A NaN is poor.
        accept = (actual <= self.accept * predicted) | first_step
        good = (actual <= self.good * predicted) & (predicted < 0)
        poor = ~((actual < self.poor * predicted) & (predicted < 0))
        length = jnp.sqrt(jnp.sum((state.scale * y_diff) ** 2))
        # The descent gives |D δ| = Δ to rounding where the radius binds; δ comes back as y_eval − y, which loses
        # digits when it is small against y: 1% tells the two cases apart. Judged before the first trial's clip.
        unbound = length < 0.99 * state.radius
        radius = jnp.where(state.tried, state.radius, jnp.minimum(state.radius, length))
        slope = jnp.dot(f_info.grad, y_diff)
        parabola = jnp.where(actual <= 0, 0.5, 0.5 * slope / (slope - actual))
        tenfold = ~(f_eval_info.f < 100.0 * f_info.f)  # |r| grew tenfold, or is not finite
        shrink = jnp.where(tenfold | ~(parabola >= 0.1), 0.1, parabola)
        kept_or_grown = jnp.where(good | unbound, 2.0 * length, radius)
        radius = jnp.where(poor, shrink * jnp.minimum(radius, 10.0 * length), kept_or_grown)
        gram = jnp.where(accept, f_eval_info.hessian.as_matrix(), f_info.hessian.as_matrix())
        largest_norms, scale = _minpack_scale(state.largest_norms, gram)
        start = self.factor * jnp.sqrt(jnp.sum((scale * y_eval) ** 2))
        radius = jnp.where(first_step, jnp.where(start > 0, start, self.factor), radius)
        return radius, accept, RESULTS.successful, _RadiusState(radius, largest_norms, scale, ~first_step)


class _State(eqx.Module):
    first_step: Any
    y_eval: Any  # the point tried next
    search_state: Any
    f_info: Any  # FunctionInfo.EvalGradHessian at the last accepted point: ½rᵀr, Jᵀr, JᵀJ
    aux: Any  # fn's auxiliary output at the last accepted point
    descent_state: Any
    terminate: Any
    result: Any
    steps: Any  # steps taken, for ``options["budget"]``


def _function_info(cost, gradient, gram):
    hessian = lx.MatrixLinearOperator(gram, lx.positive_semidefinite_tag)
    return optx.FunctionInfo.EvalGradHessian(0.5 * cost, gradient, hessian)


def normal_equations_of(fn: Callable, y, args):
    """``(rᵀr, Jᵀr, JᵀJ, aux)`` of ``fn(y, args) = (r, aux)`` at ``y`` (a vector), ``J = ∂r/∂y`` by forward mode
    (``jax.jacfwd``, one pass of ``k`` tangents), in ``y``'s dtype; ``r`` may have any shape."""

    def residuals_twice(point):
        residuals, aux = fn(point, args)
        return residuals, (residuals, aux)

    jacobian, (residuals, aux) = jax.jacfwd(residuals_twice, has_aux=True)(y)
    r = residuals.reshape(-1).astype(y.dtype)
    jacobian = jacobian.reshape(r.size, y.size).astype(y.dtype)
    return r @ r, jacobian.T @ r, jacobian.T @ jacobian, aux


class ScaledLevenbergMarquardt(optx.AbstractLeastSquaresSolver):
    """Levenberg-Marquardt for ``optx.least_squares(fn, solver, y0, args)`` with ``y0`` a vector: Marquardt-scaled
    steps (:class:`ScaledTrustRegionDescent`), a trust-region update (:class:`MinpackTrustRegion` with the
    descent's ``absolute_radius``, else :class:`CappedTrustRegion`; a pair that disagrees is refused) and MINPACK's
    stopping tests. Use it through :func:`least_squares`.

    ``rtol`` is MINPACK's ``ftol``: stop when the step just tried changed ``|r|²`` by a relative ``≤ rtol`` that
    the linear model predicted too (judged on the step tried, accepted or not, as ``lmder`` does: at the optimum
    a step predicted to gain ~1e-16 is accepted or rejected by rounding alone). ``gtol`` is MINPACK's cosine
    test: stop when every live column of ``J`` makes a cosine ``≤ gtol`` with ``r``. ``atol``: stop when
    ``|r| ≤ atol`` (an exact fit).

    ``normal_equations(y, args) -> (rᵀr, Jᵀr, JᵀJ, aux)``, when given, replaces :func:`normal_equations_of`
    ``(fn, y, args)`` in every step and must give the same sums (and ``fn``'s ``aux``); ``fn`` then only serves
    optimistix (shapes, and the derivatives of the solution). ``options={"budget": b}`` (an integer, possibly
    traced) stops after ``b`` steps as ``max_steps`` would; ``aux`` of the solution is ``fn``'s at the point
    returned.
    """

    rtol: float
    atol: float
    gtol: float
    normal_equations: Callable | None = None
    descent: ScaledTrustRegionDescent = MINPACK_DESCENT
    search: CappedTrustRegion | MinpackTrustRegion = MinpackTrustRegion()

    def __check_init__(self):
        if self.descent.absolute_radius != isinstance(self.search, MinpackTrustRegion):
            raise ValueError(
                "the descent and the search disagree on the radius: MinpackTrustRegion goes with"
                " absolute_radius=True, CappedTrustRegion with absolute_radius=False"
            )
        if self.descent.absolute_radius and not self.descent.running_scale:
            raise ValueError("MinpackTrustRegion measures steps in MINPACK's running scale: running_scale=True")

    @property  # type: ignore[misc]  # equinox lets a property implement an AbstractVar (optimistix's norm)
    def norm(self) -> Callable:  # type: ignore[override]  # as above
        """Required by optimistix's solver interface; the stopping tests here need no norm."""
        return optx.max_norm

    def init(self, fn, y, args, options, f_struct, aux_struct, tags):
        k = y.size
        f_info = _function_info(jnp.zeros((), y.dtype), jnp.zeros(k, y.dtype), jnp.zeros((k, k), y.dtype))
        return _State(
            first_step=jnp.array(True),
            y_eval=y,
            search_state=self.search.init(y, f_info),
            f_info=f_info,
            aux=jax.tree.map(lambda leaf: jnp.zeros(leaf.shape, leaf.dtype), aux_struct),
            descent_state=self.descent.init(y, f_info),
            terminate=jnp.array(False),
            result=RESULTS.successful,
            steps=jnp.zeros((), jnp.int32),
        )

    def step(self, fn, y, args, options, state, tags):
        if self.normal_equations is None:
            cost, gradient, gram, aux = normal_equations_of(fn, state.y_eval, args)
        else:
            cost, gradient, gram, aux = self.normal_equations(state.y_eval, args)
        f_eval_info = _function_info(cost, gradient, gram)
        step_size, accept, search_result, search_state = self.search.step(
            state.first_step, y, state.y_eval, state.f_info, f_eval_info, state.search_state
        )
        new_y = jnp.where(accept, state.y_eval, y)
        f_info = jax.tree.map(lambda new, old: jnp.where(accept, new, old), f_eval_info, state.f_info)
        new_aux = jax.tree.map(lambda new, old: jnp.where(accept, new, old), aux, state.aux)
        descent_state = self.descent.query(new_y, f_info, state.descent_state)

        # MINPACK's ftol, on the step just tried whether accepted or not (the class docstring).
        cost_before = 2.0 * state.f_info.f
        cost_tried = 2.0 * f_eval_info.f
        cost_after = 2.0 * f_info.f
        predicted = -2.0 * predicted_reduction(state.y_eval - y, state.f_info)
        safe_before = jnp.where(cost_before > 0, cost_before, 1.0)
        actual_relative = (cost_before - cost_tried) / safe_before
        predicted_relative = predicted / safe_before
        ftol = (
            ~state.first_step
            & (jnp.abs(actual_relative) <= self.rtol)
            & (predicted_relative <= self.rtol)
            & (actual_relative <= 2.0 * predicted_relative)
        )
        # MINPACK's gtol: the largest cosine between a Jacobian column and the residual vector.
        # Columns the descent leaves out as dead (below ε·max) are left out here too.
        squared_norms = jnp.diag(f_info.hessian.as_matrix())
        live = descent_state.live
        cosine = jnp.where(live, jnp.abs(f_info.grad) / jnp.sqrt(jnp.where(live, squared_norms, 1.0)), 0.0)
        gtol = jnp.max(cosine) <= self.gtol * jnp.sqrt(cost_after)
        exact = cost_after <= self.atol**2
        terminate = ftol | gtol | exact

        y_descent, descent_result = self.descent.step(step_size, descent_state)
        result = RESULTS.where(search_result == RESULTS.successful, descent_result, search_result)
        new_state = _State(
            first_step=jnp.array(False),
            y_eval=new_y + y_descent,
            search_state=search_state,
            f_info=f_info,
            aux=new_aux,
            descent_state=descent_state,
            terminate=terminate,
            result=result,
            steps=state.steps + 1,
        )
        return new_y, new_state, new_aux

    def terminate(self, fn, y, args, options, state, tags):
        """The stopping tests of :meth:`step`; with ``options={"budget": b}`` also a stop after ``b`` steps, reported
        as ``max_steps`` would report it: a budget is a ``max_steps`` that a program takes as an argument, so that
        one compiled solve serves a short race and the full solve."""
        if not options or "budget" not in options:
            return state.terminate, state.result
        spent = ~state.terminate & (state.steps >= options["budget"])
        result = RESULTS.where(
            spent & (state.result == RESULTS.successful), RESULTS.nonlinear_max_steps_reached, state.result
        )
        return state.terminate | spent, result

    def postprocess(self, fn, y, aux, args, options, state, tags, result):
        return y, state.aux, {}


def least_squares(
    fn: Callable,
    y0,
    args: Any = None,
    *,
    rtol: float,
    atol: float,
    gtol: float,
    max_steps: int,
    has_aux: bool = False,
    normal_equations: Callable | None = None,
    budget=None,
    descent: ScaledTrustRegionDescent = MINPACK_DESCENT,
) -> optx.Solution:
    """The least-squares solution of ``fn(y, args)`` (residuals of any shape; ``(residuals, aux)`` with
    ``has_aux``) from ``y0`` (a vector), by :class:`ScaledLevenbergMarquardt` in ``optx.least_squares``.

    ``rtol``, ``gtol``, ``atol`` are MINPACK's ``ftol``, ``gtol`` and an exact fit's ``|r|`` (the solver's
    docstring); at most ``max_steps`` steps, or ``budget`` (an integer array, an argument of a compiled program).
    ``normal_equations``: the solver's. ``descent``: MINPACK's by default (:data:`MINPACK_DESCENT`, with MINPACK's
    radius, :class:`MinpackTrustRegion`), or with the options of :class:`ScaledTrustRegionDescent`; its
    ``absolute_radius`` picks the trust-region update (:class:`CappedTrustRegion` without it, the BRDF fits').

    Returns optimistix's ``Solution`` (never raises on failure: ``solution.result`` says how the solve ended;
    ``solution.stats["num_steps"]`` counts the steps, rejected ones included; ``solution.state.f_info.f`` is
    ``½|r|²`` and ``solution.aux`` ``fn``'s aux at ``solution.value``). ``solution.value`` is differentiable with
    respect to ``args`` (and to arrays ``fn`` closes over) by the implicit function theorem (:data:`ADJOINT`);
    it has no derivative with respect to ``y0``, on which the optimum does not depend.
    """
    search = MinpackTrustRegion() if descent.absolute_radius else CappedTrustRegion()
    solver = ScaledLevenbergMarquardt(  # type: ignore[call-arg]  # norm: a property here, not a field
        rtol=rtol, atol=atol, gtol=gtol, normal_equations=normal_equations, descent=descent, search=search
    )
    return optx.least_squares(
        fn,
        solver,
        y0,
        args,
        options=None if budget is None else {"budget": budget},
        has_aux=has_aux,
        max_steps=max_steps,
        adjoint=ADJOINT,
        throw=False,
        # The Hessian of ½|r|² is symmetric: a linear solver of the adjoint may use it (lx.SVD does not need it).
        tags=frozenset({lx.symmetric_tag}),
    )
