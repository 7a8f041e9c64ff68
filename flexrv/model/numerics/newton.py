"""The one damped predictor-Newton of the condensed (massless elastic) bodies.

A condensed body's local unknowns x (the discs' rim offsets, the carrier's support
point deflections) solve R(x) = x + sign C F(x) = 0 with C the body's compliance and
F the contact forces of the element at the deflected pose (dF/dx = J, the element's
own tangent, so dR/dx = I + sign C J). Both elements run the same iteration:

1. start: the element's first-order predictor x_prev + S dq (S the previous call's
   condensed sensitivity), taken only where its change is below a tenth of the
   largest |x| (:func:`apply_predictor`; larger jumps, e.g. a solver restarting
   elsewhere, start from x_prev);
2. Newton steps ``step = (I + sign C J)^-1 R`` (:func:`~flexrv.model.numerics.linalg.condensed_step`)
   until max|R| <= tol = max(1e-15, 1e-10 max|x|) (weighted norms: the element's
   ``evaluate`` returns them), with step halving on max|R| (R is the gradient of a
   convex energy) down to lam < 1e-6, where the worse point is accepted;
3. at round-off (a worse residual while max|R| <= max(roundoff_abs, roundoff_rel tol))
   and at the caps (``max_evals`` evaluations, ``max_steps`` Newton steps) the
   iteration stops with the correction of its last evaluation in ``step``; the
   element applies that last correction linearised (F + J dx, exact to O(|R|^2)), so
   its result is smooth in q down to round-off.

The element evaluates F and J at x, the residual into ``res`` and (max|R|, max|x|) in
its weighted norm, and hands them to :func:`newton_update`, which decides the next
point (reverse communication, see there). A residual that is NaN is treated as worse
(halving). Verified bit for bit through
the elements' reference tests (tests/test_bodies.py, tests/test_housing.py,
tests/test_kernel.py) and on a scalar closed form in tests/test_elements.py.
"""

from __future__ import annotations

from numba import njit

from flexrv.model.numerics.linalg import condensed_step

#: halving stops (and the worse point is accepted) below this step fraction
MIN_STEP_FRACTION = 1e-6


@njit(cache=True)
def apply_predictor(x, dx, weight):
    """x += dx if max|dx w| <= 0.1 max|x w| (the predictor's trust rule, module
    docstring step 1); returns whether it was applied."""
    xmax, pmax = 0.0, 0.0
    for r in range(x.shape[0]):
        xmax = max(xmax, abs(x[r]) * weight[r])
        pmax = max(pmax, abs(dx[r]) * weight[r])
    if pmax <= 0.1 * xmax:
        for r in range(x.shape[0]):
            x[r] += dx[r]
        return True
    return False


@njit(cache=True)
def _tolerance(scale):
    return max(1e-15, 1e-10 * scale)


#: the slots of the iteration's state array (:func:`newton_update`): evaluations, accepted max|R|,
#: its tolerance, step fraction, Newton steps; its length
EVALS, BEST_R, TOL, LAM, STEPS = 0, 1, 2, 3, 4
NEWTON_STATE = 5
#: the slot of an element's work flags (``st``) that marks its predictor (the previous call's
#: sensitivities and state) valid: 1 valid, 0 reset (start from the stored unknowns without it)
VALID = 0


@njit(cache=True)
def newton_start(state):
    """Reset the iteration's ``state`` (NEWTON_STATE,) before the first evaluation."""
    for i in range(state.shape[0]):
        state[i] = 0.0


@njit(cache=True)
def newton_update(
    state, r1, scale, x, x0, step, res, c, j, sign, tmp, inv, max_evals, max_steps, roundoff_abs, roundoff_rel
):
    """One turn of the damped Newton (module docstring) after the element evaluated its
    residual ``res``, its tangent ``j`` (J = dF/dx) and (r1, scale) = (max|R|, max|x|)
    at x. Either sets x to the next point to evaluate and returns False, or returns
    True: done, x the last evaluated point, ``step`` its Newton correction (x - step
    solves the linearised system), ``inv`` = (I + sign C J)^-1 at it. x0, tmp: scratch.

    Reverse communication (the element calls its own residual in a loop around this
    function): one compiled iteration for every condensed body without passing compiled
    functions as arguments, which numba lowers as process addresses and then refuses to
    cache."""
    n_eval = state[EVALS] + 1.0
    state[EVALS] = n_eval
    tol1 = _tolerance(scale)
    if n_eval > 1.0 and not r1 < state[BEST_R]:  # a worse (or NaN) residual after a step
        if state[BEST_R] <= max(roundoff_abs, roundoff_rel * tol1) or n_eval >= max_evals:
            # at round-off (or out of evaluations): the correction from this last evaluation
            condensed_step(c, j, sign, res, tmp, inv, step)
            return True
        if not state[LAM] < MIN_STEP_FRACTION:
            lam = 0.5 * state[LAM]
            state[LAM] = lam
            for r in range(x.shape[0]):
                x[r] = x0[r] - lam * step[r]
            return False
        # the smallest step was worse too: accept it and go on from there
    state[BEST_R], state[TOL] = r1, tol1
    condensed_step(c, j, sign, res, tmp, inv, step)
    if r1 <= tol1 or n_eval >= max_evals or state[STEPS] >= max_steps:
        return True
    state[STEPS] += 1.0
    state[LAM] = 1.0
    for r in range(x.shape[0]):
        x0[r] = x[r]
        x[r] = x0[r] - state[LAM] * step[r]
    return False
