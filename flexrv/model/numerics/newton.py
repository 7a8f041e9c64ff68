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
   its result is smooth in q down to round-off;
4. quadratic convergence used: the residual after a full Newton step is K |step|^2
   (K the local constant of the quadratic convergence, measured in every call that
   takes a full step and evaluates again: K = max|R_next| / max|step|^2); with the
   element's estimate K_est carried from its previous calls (:func:`carry_quadratic`),
   the iteration also stops where K_est max|step|^2 <= QUAD_SAFETY tol: the next
   evaluation would only confirm a residual below the tolerance, and the linearised
   correction applied instead leaves an error of that order (N R_next, N =
   (I + sign C J)^-1 contracting). K_est = 0 (a fresh element) switches the rule off.

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
#: the quadratic-convergence stop (module docstring, step 4): the predicted next residual at most
#: this fraction of the tolerance (the rims: forces within ~1e-8 N of the converged ones, J ~ 1e9 N/m
#: times 1e-17 m, the rounding noise of the rim pose, tests/test_friction.py)
QUAD_SAFETY = 0.01
#: a carried K_est halves per measuring call unless measured larger (:func:`carry_quadratic`)
QUAD_DECAY = 0.5


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
#: its tolerance, step fraction, Newton steps, max|step| of the last full step, the largest K
#: measured in this call (0: none); its length
EVALS, BEST_R, TOL, LAM, STEPS, STEP_NORM, QUAD = 0, 1, 2, 3, 4, 5, 6
NEWTON_STATE = 7
#: the slots of an element's work flags (``st``): its predictor (the previous call's sensitivities
#: and state) valid (1; 0 reset: start from the stored unknowns without it), its carried K_est
VALID, QUAD_EST = 0, 1


@njit(cache=True)
def newton_start(state):
    """Reset the iteration's ``state`` (NEWTON_STATE,) before the first evaluation."""
    for i in range(state.shape[0]):
        state[i] = 0.0


@njit(cache=True)
def carry_quadratic(st, state):
    """After an element's iteration: its carried K_est (st[QUAD_EST]) follows the K
    measured in this call (state[QUAD]), max(K, QUAD_DECAY K_est); unchanged if none."""
    if state[QUAD] > 0.0:
        st[QUAD_EST] = max(state[QUAD], QUAD_DECAY * st[QUAD_EST])


@njit(cache=True)
def newton_update(
    state,
    r1,
    scale,
    x,
    x0,
    step,
    res,
    c,
    j,
    sign,
    tmp,
    inv,
    weight,
    quad,
    max_evals,
    max_steps,
    roundoff_abs,
    roundoff_rel,
):
    """One turn of the damped Newton (module docstring) after the element evaluated its
    residual ``res``, its tangent ``j`` (J = dF/dx) and (r1, scale) = (max|R|, max|x|)
    at x (norms weighted by ``weight``). Either sets x to the next point to evaluate and
    returns False, or returns True: done, x the last evaluated point, ``step`` its
    Newton correction (x - step solves the linearised system), ``inv`` = (I + sign C
    J)^-1 at it. ``quad``: the element's carried K_est (step 4; 0: off). x0, tmp: scratch.

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
    if n_eval > 1.0 and state[LAM] == 1.0 and state[STEP_NORM] > 0.0:  # after a full step: measure K
        state[QUAD] = max(state[QUAD], r1 / (state[STEP_NORM] * state[STEP_NORM]))
    state[BEST_R], state[TOL] = r1, tol1
    condensed_step(c, j, sign, res, tmp, inv, step)
    snorm = 0.0
    for r in range(x.shape[0]):
        snorm = max(snorm, abs(step[r]) * weight[r])
    if r1 <= tol1 or n_eval >= max_evals or state[STEPS] >= max_steps:
        return True
    if quad > 0.0 and quad * snorm * snorm <= QUAD_SAFETY * tol1:
        return True
    state[STEP_NORM] = snorm
    state[STEPS] += 1.0
    state[LAM] = 1.0
    for r in range(x.shape[0]):
        x0[r] = x[r]
        x[r] = x0[r] - state[LAM] * step[r]
    return False
