"""Tolerance analysis: the TE, lost-motion and rigidity distribution of a
production batch and which tolerance drives it (``flexrv tolerance``).

Pipeline
--------
1. **Sampling** (reproducible: the same seed gives identical samples). The
   tolerance set (:mod:`flexrv.design.tolerances`) defines D independent
   unit-interval variables (one per element and quadrature component of every
   ``per_element`` entry, one or two per ``per_reducer`` entry; ``batch``
   entries are drawn once from the seed). The unit hypercube is sampled by
   ``random`` (``numpy.random.default_rng(seed)``), ``sobol`` (scrambled Sobol',
   ``scipy.stats.qmc.Sobol(rng=seed)``) or ``lhs`` (``scipy.stats.qmc.LatinHypercube``);
   correlation groups are imposed by a Gaussian copula, then every column is
   mapped through its entry's inverse CDF (normal, truncated normal for a band,
   uniform) into error values, which replace those fields of the design's
   ``[errors]`` table.
2. **Evaluation** of every error set by the quasi-static loaded TE solver
   (:func:`flexrv.model.quasi_static.loaded_te`) as a task of the sweep machinery
   (:func:`flexrv.sweep.run_sweep`): dask.distributed (a LocalCluster of
   single-threaded worker processes, or ``--scheduler`` for a running cluster),
   samples in batches per task (the builds of a batch share the constants of the
   design without its errors), one atomically written JSON per sample under
   ``<out>/runs/cases`` keyed by a hash of the design, so a killed study resumes
   without recomputing a finished sample. ``summary.json`` ``cpu`` gives the CPU
   time of the client process and of the workers.
3. **Statistics**: percentiles P50 / P95 / P99.7 of every output, the yield (the
   fraction of samples meeting every ``--spec``) with its exact Clopper-Pearson
   95 % interval (``scipy.stats.binomtest(...).proportion_ci(method="exact")``),
   sensitivities and a what-if table (below); NetCDF ``samples.nc`` (errors in,
   outputs out), ``summary.json``, ``summary.md``, PNG histograms and a tornado chart.

Resolution of one evaluation: :data:`DEFAULT_RESOLUTION`, one crank revolution
at 2 points per pin-mesh period (78 loaded + 78 no-load positions on rv40e).
Measured on one sample (rv40e with the example error set ``iso_grade5_rv40e``,
rated torque, :func:`te_task`, compiled kernels, CPU time in a warm process):

=====================  ==========  ==========  ===========  ===========
quantity               crank, K=2  crank, K=8  output, K=2  output, K=8
=====================  ==========  ==========  ===========  ===========
TE p-p [arcsec]        53.2256     53.2256     57.1531      57.2632
mean TE [arcsec]       -124.2471   -124.2466   -124.5481    -124.5478
no-load TE p-p         50.613      50.727      68.191       68.422
lost motion [arcmin]   0.3044      0.2892      0.1756       0.1806
backlash [arcmin]      0.0920      0.0901      0.0560       0.0611
rigidity [N m/arcmin]  267.10      266.59      269.19       268.60
CPU time [s]           0.11        0.21        2.6          6.8
=====================  ==========  ==========  ===========  ===========

(crank = one crank revolution, output = one output revolution, K = points per
pin-mesh period.) Against K = 8 over the same crank revolution, K = 2 changes
TE p-p by < 1e-4, mean TE by 4e-6, no-load TE p-p by -0.2 %, lost motion by
+5 %, backlash by +2 %, rigidity by +0.2 %. Over one crank revolution the
once-per-output-revolution variation of cumulative pitch errors (disc order-1
harmonic, pin-position patterns) is not seen: TE p-p is 7 % below the
output-revolution value on this sample, lost motion and backlash are the
largest over catalog positions spread over a different range. One output
revolution costs 24x more per sample (2.6 s against 0.11 s); give
``output_revolutions=1`` (``--output-revolutions 1``) when the budget allows.

Throughput of a study (samples per second on one and two workers, start-up):
benchmarks/bench_tolerance.py; figures on the documentation's benchmark page.

Sensitivities
-------------
* Standardised regression coefficients (SRC) on the plain samples, on two
  bases (:func:`src_indices`): a linear least-squares fit of the standardised
  output on all D standardised variables (an entry's share is the sum of its
  variables' SRC^2: for independent inputs the fraction of the output variance
  the linear model attributes to it; needs N >= D + 3), and a fit on one
  feature per entry, the RMS of its standardised deviations in each reducer
  (what a max-minus-min such as TE p-p responds to; needs N >= G + 3). The
  ranking uses the basis with the higher adjusted R^2, which is reported: a low
  R^2 means the output is not explained linearly (use ``--sobol``).
* With ``--sobol``: first-order and total Sobol' indices per tolerance entry
  (SALib, grouped variables) on a Saltelli design of N (G + 2) evaluations, G =
  number of entries; its A and B blocks (2N quasi-random samples) are the plain
  samples of the distribution statistics. A base sample with a failed
  evaluation is left out of the indices (``sobol_base_samples_used``).

What-if table
-------------
Estimated by **re-evaluation**: the first M plain samples (``what_if_samples``)
are re-run with one entry's deviations from its mean scaled by 0.5 and by 2
(exactly the samples of the halved / doubled tolerance: sigma, band and bounds
scale together), every other error unchanged. The table gives P95 of TE p-p,
the median lost motion and the yield on those M samples beside the same M samples
unscaled (a paired comparison: the difference is the tolerance's effect; the
absolute values carry the sampling error of M samples). Cost: 2 G M extra
evaluations (G: the entries of ``what_if_entries``, default all).
"""

from __future__ import annotations

import json
import math
import os
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from flexrv.errors import ConfigError, InputError

#: Outputs of one evaluation (keys of :meth:`flexrv.model.quasi_static.LoadedTE.summary`).
OUTPUTS = (
    "te_pp_arcsec",
    "te_mean_arcsec",
    "no_load_te_pp_arcsec",
    "lost_motion_arcmin",
    "backlash_arcmin",
    "torsional_rigidity_Nm_per_arcmin",
)

#: Default resolution of one evaluation (accuracy and cost measured in the module
#: docstring): one crank revolution at 2 points per pin-mesh period. force_tol
#: 1e-6 (of T_rated / a_w, ~0.01 N on rv40e, 1e-5 of a rated pin force; measured
#: against 1e-7 on the example error set: TE p-p and mean TE change by < 1e-6
#: arcsec) and max_iter 200: with errors, the solver's default 1e-7 / 60 stalled
#: just above its tolerance at some positions (measured 0.0013 N vs 0.0011 N).
DEFAULT_RESOLUTION = {
    "crank_revolutions": 1.0,
    "output_revolutions": None,
    "points_per_mesh": 2,
    "force_tol": 1e-6,
    "max_iter": 200,
    "torque": None,
}

_SPEC = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*(<=|>=|<|>)\s*([-+0-9.eEinfINFaA]+)\s*$")


# ----------------------------------------------------------------------------- evaluation task
#: Solver settings tried in turn when the static solver stalls (see :func:`te_task`).
SOLVER_LADDER = ((1.0, 1.0), (0.1, 1.0), (1.0, 5.0))


def loaded_te_with_retries(reducer, force_tol: float, max_iter: int, **kw):
    """:func:`flexrv.model.quasi_static.loaded_te` of ``reducer`` (``kw``: its other keywords)
    with the static solver's ``force_tol`` and ``max_iter``; where it stalls (ConvergenceError),
    solved again with the next settings of :data:`SOLVER_LADDER`. Returns (result, the index
    of the attempt that succeeded); the last attempt's error is raised if none does."""
    from flexrv.errors import ConvergenceError
    from flexrv.model.quasi_static import loaded_te

    last = None
    for attempt, (f_tol, f_it) in enumerate(SOLVER_LADDER):
        try:
            options = {"force_tol": force_tol * f_tol, "max_iter": int(max_iter * f_it)}
            return loaded_te(reducer, options=options, **kw), attempt
        except ConvergenceError as exc:
            last = exc
    raise last


def te_task(
    reducer,
    crank_revolutions: float | None = 1.0,
    output_revolutions: float | None = None,
    points_per_mesh: int = 2,
    force_tol: float = 1e-6,
    max_iter: int = 200,
    torque: float | None = None,
) -> dict[str, float]:
    """One tolerance sample: the quasi-static loaded TE summary numbers (:data:`OUTPUTS`).

    With errors the static solver sometimes stalls a little above its residual
    tolerance at a position where the contact set changes (measured: residual
    0.03 N vs 0.011 N); the stall depends on the iteration history, so the
    sample is re-solved with the tolerance x0.1 and then with max_iter x5
    (:data:`SOLVER_LADDER`, :func:`loaded_te_with_retries`) before it is recorded as
    failed. Every attempt solves the same equations to a residual below 1e-5 of a rated
    pin force, so the outputs agree to far below the sampling scatter; ``attempt`` records
    which one succeeded."""
    if output_revolutions is not None:
        crank_revolutions = None
    res, attempt = loaded_te_with_retries(
        reducer,
        force_tol,
        max_iter,
        torque=torque,
        output_revolutions=output_revolutions,
        crank_revolutions=crank_revolutions,
        points_per_mesh=points_per_mesh,
    )
    s = res.summary()
    out = {k: float(s[k]) for k in OUTPUTS}
    out["positions"] = int(s["positions"])
    out["solve_time_s"] = float(s["solve_time_s"])
    out["attempt"] = attempt
    return out


te_task.outputs = OUTPUTS  # declared for the sweep machinery's output check


# ----------------------------------------------------------------------------- specs
@dataclass(frozen=True)
class Spec:
    """A specification limit ``output <op> value``."""

    output: str
    op: str
    value: float

    def ok(self, y: np.ndarray) -> np.ndarray:
        return {"<=": y <= self.value, ">=": y >= self.value, "<": y < self.value, ">": y > self.value}[self.op]

    def __str__(self) -> str:
        return f"{self.output}{self.op}{self.value:g}"


def parse_spec(text: str) -> Spec:
    """``"te_pp_arcsec<=60"`` -> Spec; InputError naming the problem."""
    m = _SPEC.match(str(text))
    if not m:
        raise InputError(f"--spec {text!r}: bad syntax; write OUTPUT<=VALUE (or >=, <, >), e.g. te_pp_arcsec<=60")
    name, op, val = m.groups()
    if name not in OUTPUTS:
        raise InputError(f"--spec {text!r}: unknown output {name!r}; allowed: {', '.join(OUTPUTS)}")
    try:
        v = float(val)
    except ValueError:
        raise InputError(f"--spec {text!r}: limit {val!r} is not a number") from None
    if not math.isfinite(v):
        raise InputError(f"--spec {text!r}: limit must be finite")
    return Spec(name, op, v)


# ----------------------------------------------------------------------------- sampling plan
@dataclass
class Column:
    """One unit-interval variable of the hypercube."""

    entry: str
    label: str  #: e.g. "pins.pin_radius_um[3]"


@dataclass
class TolerancePlan:
    """Variables of a tolerance set and their mapping to error tables."""

    reducer: Any
    tol: Any  #: flexrv.design.tolerances.ToleranceSet
    seed: int
    columns: list[Column] = field(default_factory=list)
    slices: dict[str, slice] = field(default_factory=dict)
    batch_values: dict[str, np.ndarray] = field(default_factory=dict)

    @classmethod
    def build(cls, reducer, tol, seed: int) -> "TolerancePlan":
        plan = cls(reducer, tol, int(seed))
        rng = np.random.default_rng([int(seed), 0xBA7C4])  # the batch's own stream
        for key, t in tol.entries.items():
            info = tol.fields[key]
            if t.scope == "per_element":
                labels = list(info.labels)
            else:
                labels = [".cos", ".sin"] if info.vector else [""]
            if t.scope == "batch":
                plan.batch_values[key] = plan.inverse_cdf(key, rng.random(len(labels)))
                continue
            start = len(plan.columns)
            plan.columns += [Column(key, f"{key}{lab}") for lab in labels]
            plan.slices[key] = slice(start, len(plan.columns))
        if not plan.columns and not plan.batch_values:
            raise ConfigError("[tolerances]: no entries")
        return plan

    @property
    def dim(self) -> int:
        return len(self.columns)

    @property
    def groups(self) -> list[str]:
        """Entries with variables (the sensitivity groups), in table order."""
        return list(self.slices)

    # --- unit samples
    def unit_samples(self, n: int, sampler: str) -> np.ndarray:
        """(n, D) points of the unit hypercube, reproducible from the seed."""
        d = self.dim
        if d == 0:
            return np.zeros((n, 0))
        if sampler == "random":
            return np.random.default_rng(self.seed).random((n, d))
        from scipy.stats import qmc

        engines = {"sobol": qmc.Sobol, "lhs": qmc.LatinHypercube}
        if sampler in engines:
            import warnings

            try:  # scipy >= 1.15 names the seed 'rng'
                engine = engines[sampler](d, scramble=True, rng=self.seed)
            except TypeError:
                engine = engines[sampler](d, scramble=True, seed=self.seed)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # Sobol' balance warning for n not a power of 2
                return engine.random(n)
        raise InputError(f"--sampler {sampler!r}: allowed random, sobol, lhs")

    def saltelli(self, n: int) -> np.ndarray:
        """SALib Saltelli design (first and total order) on grouped variables:
        n (G + 2) rows, block layout [A, AB_1..AB_G, B] per base sample."""
        import warnings

        from SALib.sample import sobol as sobol_sample

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return sobol_sample.sample(self.salib_problem(), n, calc_second_order=False, seed=self.seed)

    def salib_problem(self) -> dict[str, Any]:
        return {
            "num_vars": self.dim,
            "names": [c.label for c in self.columns],
            "bounds": [[0.0, 1.0]] * self.dim,
            "groups": [c.entry for c in self.columns],
        }

    # --- unit -> values
    def correlate(self, u: np.ndarray) -> np.ndarray:
        """Impose the correlation groups (Gaussian copula; marginals unchanged)."""
        from scipy.stats import norm

        u = np.array(u, dtype=float, copy=True)
        for corr in self.tol.correlations:
            keys = [k for k in corr.fields if k in self.slices]
            if len(keys) < 2:
                continue
            k = len(keys)
            c = np.full((k, k), corr.coefficient)
            np.fill_diagonal(c, 1.0)
            chol = np.linalg.cholesky(c + 1e-12 * np.eye(k))
            cols = np.stack([np.arange(self.slices[key].start, self.slices[key].stop) for key in keys])  # (k, m)
            z = norm.ppf(np.clip(u[:, cols], 1e-15, 1 - 1e-15))  # (n, k, m)
            z = np.einsum("ij,njm->nim", chol, z)
            u[:, cols] = norm.cdf(z)
        return u

    def inverse_cdf(self, key: str, u: np.ndarray) -> np.ndarray:
        """Values [field unit] of an entry's distribution at probabilities u."""
        from scipy.stats import norm, truncnorm

        t = self.tol.entries[key]
        u = np.clip(np.asarray(u, dtype=float), 1e-15, 1 - 1e-15)
        if t.distribution == "normal":
            return t.mean + t.sigma * norm.ppf(u)
        if t.distribution == "uniform":
            return t.mean + t.band * (2.0 * u - 1.0)
        c = 1.0 / t.sigma_fraction
        return truncnorm.ppf(u, -c, c, loc=t.mean, scale=t.band * t.sigma_fraction)

    def values(self, u: np.ndarray) -> np.ndarray:
        """(n, D) error values from (n, D) unit samples (correlations applied)."""
        u = self.correlate(np.atleast_2d(u))
        x = np.empty_like(u)
        for key, sl in self.slices.items():
            x[:, sl] = self.inverse_cdf(key, u[:, sl])
        return x

    # --- values -> [errors] table
    def errors_for(self, x_row: np.ndarray, scale: dict[str, float] | None = None) -> dict[str, Any]:
        """The ``[errors]`` table (plain dict) of one sample; ``scale`` multiplies
        an entry's deviations from its mean (what-if)."""
        from flexrv.design.manufacturing import DiscErrors

        scale = scale or {}
        errors = self.reducer.errors.model_dump(mode="python")
        nd = self.reducer.second_stage.n_discs
        if not errors["discs"]:
            errors["discs"] = [DiscErrors().model_dump(mode="python") for _ in range(nd)]
        for key, t in self.tol.entries.items():
            info = self.tol.fields[key]
            raw = self.batch_values[key] if t.scope == "batch" else np.asarray(x_row)[self.slices[key]]
            raw = t.mean + scale.get(key, 1.0) * (np.asarray(raw, dtype=float) - t.mean)
            if t.scope == "per_element":
                v = raw.reshape(info.shape)
            else:
                base = np.zeros(info.shape)
                v = base + (raw.reshape((2,)) if info.vector else raw[0])
            _assign(errors, key, v)
        return errors


def _assign(errors: dict, key: str, v: np.ndarray) -> None:
    """Write drawn values into an [errors] dict (amplitude/phase from quadrature
    components (A cos p, A sin p))."""
    group, _, name = key.partition(".")
    m = re.match(r"^harmonic_order_(\d+)_um$", name)
    if m:
        order = int(m.group(1))
        for k, disc in enumerate(errors["discs"]):
            amp, ph = float(np.hypot(v[k, 0], v[k, 1])), float(np.degrees(np.arctan2(v[k, 1], v[k, 0])))
            harms = [h for h in disc["harmonics"] if h["order"] != order]
            harms.append({"order": order, "amplitude_um": amp, "phase_deg": ph})
            disc["harmonics"] = sorted(harms, key=lambda h: h["order"])
        return
    if key in ("first_stage.sun_runout_um", "first_stage.planet_runout_um"):
        amp = np.hypot(v[..., 0], v[..., 1])
        ph = np.degrees(np.arctan2(v[..., 1], v[..., 0]))
        errors[group][name] = _plain(amp)
        errors[group][name.replace("_um", "_phase_deg")] = _plain(ph)
        return
    if group == "discs":
        for k, disc in enumerate(errors["discs"]):
            disc[name] = _plain(v[k])
        return
    errors[group][name] = _plain(v)


def _plain(a: np.ndarray) -> Any:
    a = np.asarray(a, dtype=float)
    return float(a) if a.ndim == 0 else a.tolist()


# ----------------------------------------------------------------------------- statistics
def percentiles(y: np.ndarray) -> dict[str, float]:
    """P50 / P95 / P99.7, mean, std of the finite values (linear interpolation)."""
    y = y[np.isfinite(y)]
    if y.size == 0:
        return {"n": 0}
    p50, p95, p997 = np.percentile(y, [50.0, 95.0, 99.7])
    return {
        "n": int(y.size),
        "mean": float(np.mean(y)),
        "std": float(np.std(y, ddof=1)) if y.size > 1 else 0.0,
        "min": float(np.min(y)),
        "P50": float(p50),
        "P95": float(p95),
        "P99.7": float(p997),
        "max": float(np.max(y)),
    }


def yield_estimate(ys: dict[str, np.ndarray], specs: list[Spec], confidence: float = 0.95) -> dict[str, Any] | None:
    """Fraction of (finite) samples meeting every spec and its exact
    Clopper-Pearson interval."""
    if not specs:
        return None
    from scipy.stats import binomtest

    n_all = len(next(iter(ys.values())))
    finite = np.all([np.isfinite(ys[s.output]) for s in specs], axis=0) if n_all else np.zeros(0, bool)
    good = finite.copy()
    for s in specs:
        with np.errstate(invalid="ignore"):
            good &= s.ok(ys[s.output])
    n, k = int(finite.sum()), int(good.sum())
    if n == 0:
        return {"n": 0, "passed": 0, "yield": None, "ci_low": None, "ci_high": None, "specs": [str(s) for s in specs]}
    ci = binomtest(k, n).proportion_ci(confidence_level=confidence, method="exact")
    return {
        "n": n,
        "passed": k,
        "yield": k / n,
        "ci_low": float(ci.low),
        "ci_high": float(ci.high),
        "confidence": confidence,
        "specs": [str(s) for s in specs],
    }


def _src(features: np.ndarray, names: list[str], y: np.ndarray, entries: list[str]) -> dict[str, Any] | None:
    """Least-squares SRCs of y on the feature columns, SRC^2 summed per entry,
    R^2 and adjusted R^2; None if there are too few samples for the fit."""
    sx = np.std(features, axis=0)
    keep = sx > 0
    n, p = len(y), int(keep.sum())
    if n < p + 3 or p == 0:
        return None
    xs = (features[:, keep] - features[:, keep].mean(axis=0)) / sx[keep]
    ys = (y - y.mean()) / np.std(y)
    beta, *_ = np.linalg.lstsq(xs, ys, rcond=None)
    resid = ys - xs @ beta
    r2 = 1.0 - float(resid @ resid) / float(ys @ ys)
    kept = [g for g, k in zip(names, keep) if k]
    share = {e: float(sum(b * b for g, b in zip(kept, beta) if g == e)) for e in entries}
    return {
        "r2": r2,
        "r2_adjusted": 1.0 - (1.0 - r2) * (n - 1) / (n - p - 1),
        "features": p,
        "indices": dict(sorted(share.items(), key=lambda kv: -kv[1])),
    }


def src_indices(x: np.ndarray, y: np.ndarray, plan: "TolerancePlan") -> dict[str, Any]:
    """Standardised regression coefficients of an output on two bases (see the
    module docstring): ``variables`` (every sampled variable, SRC^2 summed per
    entry; needs N >= D + 3) and ``magnitudes`` (one feature per entry: the RMS
    of its standardised deviations in that reducer, what a max-minus-min such as
    TE p-p responds to; needs N >= G + 3). ``best`` names the basis with the
    higher adjusted R^2 (the ranking uses it)."""
    ok = np.isfinite(y)
    x, y = x[ok], y[ok]
    out: dict[str, Any] = {"n": int(len(y)), "best": None}
    if len(y) < 3 or np.std(y) == 0.0:
        return out
    entries = plan.groups
    cols = [c.entry for c in plan.columns]
    out["variables"] = _src(x, cols, y, entries)
    z = np.empty((len(y), len(entries)))
    for i, e in enumerate(entries):
        xe = x[:, plan.slices[e]]
        sd = np.std(xe, axis=0)
        sd[sd == 0] = 1.0
        z[:, i] = np.sqrt(np.mean(((xe - xe.mean(axis=0)) / sd) ** 2, axis=1))
    out["magnitudes"] = _src(z, entries, y, entries)
    fits = [(v["r2_adjusted"], k) for k in ("variables", "magnitudes") if (v := out.get(k))]
    if fits:
        out["best"] = max(fits)[1]
    return out


def sobol_indices(problem: dict[str, Any], y: np.ndarray, seed: int = 0) -> dict[str, Any]:
    """First-order and total Sobol' indices per group (SALib, Saltelli estimators)."""
    import warnings

    from SALib.analyze import sobol as sobol_analyze

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sobol_analyze.analyze(
            problem, np.asarray(y, dtype=float), calc_second_order=False, seed=seed, print_to_console=False
        )
    names = list(dict.fromkeys(problem.get("groups") or problem["names"]))
    out = {
        name: {
            "S1": float(res["S1"][i]),
            "S1_conf": float(res["S1_conf"][i]),
            "ST": float(res["ST"][i]),
            "ST_conf": float(res["ST_conf"][i]),
        }
        for i, name in enumerate(names)
    }
    return dict(sorted(out.items(), key=lambda kv: -kv[1]["ST"]))


# ----------------------------------------------------------------------------- the study
@dataclass
class StudyConfig:
    """Arguments of :func:`run_study`."""

    design: str
    samples: int
    seed: int = 0
    sampler: str = "sobol"
    specs: list[str] = field(default_factory=list)
    tolerances: str | None = None
    scheduler: str | None = None
    workers: int | None = None
    sobol: bool = False
    out: str | None = None
    what_if_samples: int = 16
    #: tolerance entries of the what-if table (None: every entry; cost 2 M per entry)
    what_if_entries: list[str] | None = None
    resolution: dict[str, Any] = field(default_factory=lambda: dict(DEFAULT_RESOLUTION))
    #: allow more local workers than the machine has cores
    force: bool = False
    #: samples per dask task (None: :func:`flexrv.sweep.batch_size` of the samples and workers)
    batch: int | None = None


def _validate(cfg: StudyConfig) -> list[Spec]:
    from flexrv.sweep import MAX_CASES, check_scheduler, check_workers

    if isinstance(cfg.samples, bool) or not isinstance(cfg.samples, int) or not 1 <= cfg.samples <= MAX_CASES:
        raise InputError(
            f"--samples {cfg.samples!r}: must be an integer from 1 to {MAX_CASES} (the most cases one sweep may run)"
        )
    if cfg.sobol and cfg.samples < 2:
        raise InputError(f"--samples {cfg.samples}: a Saltelli design needs at least 2 base samples")
    if cfg.sampler not in ("random", "sobol", "lhs"):
        raise InputError(f"--sampler {cfg.sampler!r}: allowed random, sobol, lhs")
    check_workers(cfg.workers, cfg.force)
    if cfg.batch is not None and (isinstance(cfg.batch, bool) or not isinstance(cfg.batch, int) or cfg.batch < 1):
        raise InputError(f"batch {cfg.batch!r}: must be an integer >= 1 (samples per dask task)")
    if cfg.what_if_samples < 0:
        raise InputError(f"--what-if-samples {cfg.what_if_samples}: must be >= 0")
    if cfg.what_if_entries is not None and not isinstance(cfg.what_if_entries, (list, tuple)):
        raise InputError(f"what_if_entries {cfg.what_if_entries!r}: must be a list of tolerance entries")
    if not isinstance(cfg.seed, int) or cfg.seed < 0:
        raise InputError(f"--seed {cfg.seed!r}: must be an integer >= 0")
    unknown = set(cfg.resolution) - set(DEFAULT_RESOLUTION)
    if unknown:
        raise InputError(f"unknown resolution option(s) {sorted(unknown)}; allowed {sorted(DEFAULT_RESOLUTION)}")
    specs = [parse_spec(s) for s in cfg.specs]
    if cfg.scheduler:
        check_scheduler(cfg.scheduler)
    return specs


def load_design_and_tolerances(design: str, tolerances: str | None):
    """(Reducer, ToleranceSet, design path for the sweep machinery or None)."""
    from flexrv.design import from_dict, load
    from flexrv.design.tolerances import design_tolerance_table, load_tolerances, parse_tolerances

    table, data = design_tolerance_table(design)
    if data is not None:
        reducer = from_dict(data, source=str(design))
    else:
        reducer = load(design)
    if tolerances is not None:
        tol = load_tolerances(tolerances, reducer)
    elif table is not None:
        tol = parse_tolerances(table, reducer, source=str(design))
    else:
        raise ConfigError(f"{design}: no [tolerances] table; add one to the design TOML or give --tolerances FILE")
    return reducer, tol, data


def plan_cases(cfg: StudyConfig, reducer, tol) -> tuple[TolerancePlan, dict[str, Any]]:
    """The study's samples: plain unit samples U and values X, optional Saltelli
    rows, what-if cases. Returns (plan, parts) with parts["cases"] a list of
    (kind, index, entry, factor, errors dict)."""
    plan = TolerancePlan.build(reducer, tol, cfg.seed)
    parts: dict[str, Any] = {}
    g = len(plan.groups)
    if cfg.sobol and plan.dim:
        u_all = plan.saltelli(cfg.samples)
        x_all = plan.values(u_all)
        step = g + 2
        plain_idx = np.sort(np.r_[np.arange(0, len(u_all), step), np.arange(step - 1, len(u_all), step)])
        parts["saltelli_u"], parts["saltelli_x"] = u_all, x_all
        u, x = u_all[plain_idx], x_all[plain_idx]
        parts["plain_in_saltelli"] = plain_idx
    else:
        u = plan.unit_samples(cfg.samples, cfg.sampler)
        x = plan.values(u) if plan.dim else np.zeros((cfg.samples, 0))
    parts["u"], parts["x"] = u, x
    cases = [("sample", i, "", 1.0, plan.errors_for(x[i])) for i in range(len(x))]
    if cfg.sobol and plan.dim:
        done = set(parts["plain_in_saltelli"].tolist())
        cases += [
            ("saltelli", i, "", 1.0, plan.errors_for(parts["saltelli_x"][i]))
            for i in range(len(parts["saltelli_x"]))
            if i not in done
        ]
    m = min(cfg.what_if_samples, len(x))
    what_if = list(tol.entries) if cfg.what_if_entries is None else list(cfg.what_if_entries)
    unknown = [k for k in what_if if k not in tol.entries]
    if unknown:
        raise InputError(f"what-if entries {unknown} are not in the tolerance set; allowed: {sorted(tol.entries)}")
    for key in what_if:
        for f in (0.5, 2.0):
            cases += [("what_if", i, key, f, plan.errors_for(x[i], {key: f})) for i in range(m)]
    parts["cases"] = cases
    parts["what_if_m"] = m
    return plan, parts


def run_study(cfg: StudyConfig, progress: bool = True) -> dict[str, Any]:
    """Run (or resume) a tolerance study; returns the summary dict (also written
    to ``<out>/summary.json``)."""

    specs = _validate(cfg)
    reducer, tol, design_data = load_design_and_tolerances(cfg.design, cfg.tolerances)
    out = Path(cfg.out) if cfg.out else Path("results") / f"{Path(cfg.design).stem}_tolerance_s{cfg.seed}"
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out} is an existing file: give a directory")
    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    try:
        return _run_in(out, cfg, specs, reducer, tol, design_data, progress)
    except BaseException:
        # a study refused (or stopped) before its first stored case leaves no folder behind (a
        # case still being written when the study stopped is not stored)
        from flexrv.cache import finished_files

        if created and not finished_files(out / "runs" / "cases"):
            import shutil

            shutil.rmtree(out, ignore_errors=True)
        raise


def _run_in(out: Path, cfg: StudyConfig, specs, reducer, tol, design_data, progress: bool) -> dict[str, Any]:
    """The body of :func:`run_study` once the output folder exists."""
    from flexrv.cache import atomic_write_text
    from flexrv.model.quasi_static import positions_for
    from flexrv.sweep import SweepSpec, process_cpu_s, run_sweep

    client_cpu0 = process_cpu_s()
    res = {**DEFAULT_RESOLUTION, **cfg.resolution}

    positions_for(
        reducer,
        res["output_revolutions"],
        None if res["output_revolutions"] else res["crank_revolutions"],
        res["points_per_mesh"],
    )  # bad resolution -> InputError now, not on every worker
    plan, parts = plan_cases(cfg, reducer, tol)
    preset = cfg.design
    if design_data is not None:  # the design file carries [tolerances]: the sweep reads the design without it
        import tomli_w

        preset = str(out / "design.toml")
        atomic_write_text(preset, tomli_w.dumps(design_data))
    spec = SweepSpec(
        name=f"tolerance-{reducer.name}",
        preset=preset,
        task="flexrv.studies.tolerance:te_task",
        outputs=list(OUTPUTS),
        options=res,
        cases=[{"errors": c[4]} for c in parts["cases"]],
        description="flexrv tolerance study samples",
    )
    t0 = time.perf_counter()
    workers = cfg.workers or min(2, os.cpu_count() or 1)
    summary_sweep = run_sweep(
        spec,
        out_dir=out / "runs",
        scheduler=cfg.scheduler,
        n_workers=workers,
        progress=progress,
        plots=False,
        force=cfg.force,
        batch=cfg.batch,
    )  # the study draws its own figures
    wall = time.perf_counter() - t0
    ids = summary_sweep.case_ids
    records = []
    for cid in ids:
        path = out / "runs" / "cases" / f"{cid}.json"
        records.append(json.loads(path.read_text()) if path.exists() else {"status": "missing"})
    y = np.full((len(records), len(OUTPUTS)), np.nan)
    status = []
    for i, r in enumerate(records):
        status.append(r.get("status", "missing"))
        if r.get("status") == "ok":
            y[i] = [np.nan if r["result"].get(k) is None else float(r["result"][k]) for k in OUTPUTS]
    n_plain = len(parts["x"])
    y_plain = y[:n_plain]
    ys = {k: y_plain[:, j] for j, k in enumerate(OUTPUTS)}
    result: dict[str, Any] = {
        "design": reducer.name,
        "samples": n_plain,
        "seed": cfg.seed,
        "sampler": "saltelli (sobol)" if cfg.sobol else cfg.sampler,
        "variables": plan.dim,
        "evaluations": len(records),
        "computed_now": summary_sweep.computed,
        "skipped_existing": summary_sweep.skipped,
        "failed": int(sum(s != "ok" for s in status)),
        "failed_plain": int(sum(s != "ok" for s in status[:n_plain])),
        "wall_time_s": wall,
        "cpu": summary_sweep.cpu.as_dict(),
        "resolution": res,
        "tolerances": tol.to_dict(),
        "percentiles": {k: percentiles(ys[k]) for k in OUTPUTS},
        "yield": yield_estimate(ys, specs),
    }
    result["sensitivity_src"] = (
        {k: src_indices(parts["x"], ys[k], plan) for k in ("te_pp_arcsec", "te_mean_arcsec", "lost_motion_arcmin")}
        if plan.dim
        else {}
    )
    if cfg.sobol and plan.dim:
        n_salt = len(parts["saltelli_x"])
        y_salt = np.full((n_salt, len(OUTPUTS)), np.nan)
        y_salt[parts["plain_in_saltelli"]] = y_plain
        extra = [i for i in range(n_salt) if i not in set(parts["plain_in_saltelli"].tolist())]
        y_salt[extra] = y[n_plain : n_plain + len(extra)]
        sob, used = {}, {}
        step = len(plan.groups) + 2
        for j, k in enumerate(OUTPUTS[:4]):
            # a failed evaluation removes its whole base sample (block [A, AB_1..AB_G, B])
            blocks = y_salt[:, j].reshape(-1, step)
            keep = np.all(np.isfinite(blocks), axis=1)
            if keep.sum() >= 2:
                sob[k] = sobol_indices(plan.salib_problem(), blocks[keep].ravel(), cfg.seed)
            else:
                sob[k] = {"error": f"only {int(keep.sum())} base samples without a failed evaluation"}
            used[k] = int(keep.sum())
        result["sensitivity_sobol"] = sob
        result["sobol_base_samples_used"] = used
    result["what_if"] = _what_if(parts, y, specs)
    result["ranked_sensitivities"] = _ranking(result)
    _write_outputs(out, cfg, plan, parts, y_plain, status[:n_plain], ids[:n_plain], specs, result)
    result["cpu"]["client_study_cpu_s"] = process_cpu_s() - client_cpu0  # sampling, cluster, outputs included
    result["output_dir"] = str(out)
    atomic_write_text(out / "summary.json", json.dumps(_jsonable(result), indent=1))
    return result


def _what_if(parts, y, specs) -> dict[str, Any]:
    """What-if rows (see module docstring). Paired: for each tolerance only the
    samples whose unscaled, halved and doubled evaluations all succeeded count
    (a failed evaluation would otherwise bias one side); ``samples_used`` says
    how many."""
    m = parts["what_if_m"]
    if m == 0:
        return {"samples": 0, "rows": []}
    j = OUTPUTS.index("te_pp_arcsec")
    j_lm = OUTPUTS.index("lost_motion_arcmin")
    need = sorted({j, j_lm, *(OUTPUTS.index(s.output) for s in specs)})
    idx: dict[tuple[str, float], list[int]] = {}
    for pos, c in enumerate(parts["cases"]):
        if c[0] == "what_if":
            idx.setdefault((c[2], c[3]), []).append(pos)

    def stats(block):
        p95 = float(np.percentile(block[:, j], 95.0)) if len(block) else None
        yl = yield_estimate({k: block[:, i] for i, k in enumerate(OUTPUTS)}, specs) if len(block) else None
        lm50 = float(np.percentile(block[:, j_lm], 50.0)) if len(block) else None
        return p95, (yl["yield"] if yl else None), lm50

    rows = []
    for (key, f), pos in idx.items():
        if f != 0.5:
            continue
        blocks = [y[:m], y[pos], y[idx[(key, 2.0)]]]
        ok = np.all([np.all(np.isfinite(b[:, need]), axis=1) for b in blocks], axis=0)
        (p0, y0, l0), (ph, yh, lh), (pd, yd, ld) = (stats(b[ok]) for b in blocks)
        rows.append(
            {
                "tolerance": key,
                "samples_used": int(ok.sum()),
                "p95_te_pp_arcsec": p0,
                "p95_te_pp_arcsec_halved": ph,
                "p95_te_pp_arcsec_doubled": pd,
                "yield": y0,
                "yield_halved": yh,
                "yield_doubled": yd,
                "p50_lost_motion_arcmin": l0,
                "p50_lost_motion_arcmin_halved": lh,
                "p50_lost_motion_arcmin_doubled": ld,
            }
        )
    rows.sort(key=lambda r: -abs((r["p95_te_pp_arcsec_doubled"] or 0.0) - (r["p95_te_pp_arcsec_halved"] or 0.0)))
    return {
        "samples": m,
        "method": "re-evaluation of the first M plain samples with the tolerance's deviations "
        "scaled by 0.5 / 2, paired with the same samples unscaled (samples with a "
        "failed evaluation left out of that row)",
        "rows": rows,
    }


def _ranking(result) -> dict[str, list[dict[str, Any]]]:
    """Ranked sensitivities per output: Sobol' ST if computed, else SRC^2 of the
    better-fitting basis (empty if too few samples for either)."""
    out = {}
    sob = result.get("sensitivity_sobol", {})
    for k, v in result.get("sensitivity_src", {}).items():
        if k in sob and "error" not in sob[k]:
            out[k] = [{"tolerance": e, "ST": s["ST"], "S1": s["S1"], "method": "sobol"} for e, s in sob[k].items()]
        elif v.get("best"):
            fit = v[v["best"]]
            out[k] = [
                {"tolerance": e, "src2": s, "method": f"src ({v['best']})", "r2": fit["r2"]}
                for e, s in fit["indices"].items()
            ]
        else:
            out[k] = []
    return out


def _jsonable(obj):
    from flexrv.cache import to_jsonable

    return to_jsonable(obj)


# ----------------------------------------------------------------------------- outputs
def _write_outputs(out: Path, cfg, plan, parts, y, status, ids, specs, result) -> None:
    import xarray as xr

    from flexrv.cache import atomic_path, atomic_write_text

    n = len(y)
    data = {
        "u": (("sample", "variable"), np.asarray(parts["u"], dtype=float)),
        "x": (("sample", "variable"), np.asarray(parts["x"], dtype=float)),
        "status": ("sample", np.asarray(status, dtype=str)),
        "case_id": ("sample", np.asarray(ids, dtype=str)),
    }
    for j, k in enumerate(OUTPUTS):
        data[k] = ("sample", y[:, j])
    ds = xr.Dataset(
        data,
        coords={
            "sample": np.arange(n),
            "variable": [c.label for c in plan.columns],
            "tolerance": ("variable", [c.entry for c in plan.columns]),
        },
        attrs={
            "design": plan.reducer.name,
            "seed": cfg.seed,
            "sampler": result["sampler"],
            "tolerances": json.dumps(plan.tol.to_dict()),
            "resolution": json.dumps(result["resolution"]),
            "batch_values": json.dumps({k: v.tolist() for k, v in plan.batch_values.items()}),
            "x_units": "each variable in the unit of its error field (um or arcmin)",
            "specs": json.dumps([str(s) for s in specs]),
        },
    )
    with atomic_path(out / "samples.nc") as tmp:
        ds.to_netcdf(tmp, engine="h5netcdf")
    # no figure of a study without one successful sample (an empty histogram says nothing)
    plots = [_histograms(out, y, specs), _tornado(out, result)] if np.isfinite(y).any() else []
    for stale in ("histograms.png", "tornado.png"):
        if not plots:
            (out / stale).unlink(missing_ok=True)
    result["plots"] = [str(p) for p in plots if p]
    atomic_write_text(out / "summary.md", _markdown(result))


def _histograms(out: Path, y: np.ndarray, specs: list[Spec]) -> Path:
    from flexrv.viz.plots import _plt, _save

    plt = _plt()
    fig, axes = plt.subplots(2, 3, figsize=(13, 7))
    for ax, (j, k) in zip(axes.ravel(), enumerate(OUTPUTS)):
        v = y[:, j][np.isfinite(y[:, j])]
        if v.size:
            ax.hist(v, bins=max(5, min(50, int(np.sqrt(v.size)) * 2)), color="0.6")
            for q, style in ((50.0, "-"), (95.0, "--"), (99.7, ":")):
                p = np.percentile(v, q)
                ax.axvline(p, color="C0", ls=style, label=f"P{q:g} = {p:.4g}")
        for s in specs:
            if s.output == k:
                ax.axvline(s.value, color="C3", lw=2, label=f"spec {s}")
        ax.set_xlabel(k)
        ax.set_ylabel("samples")
        ax.legend(fontsize=7)
    fig.suptitle(f"tolerance study: {len(y)} samples")
    fig.tight_layout()
    return _save(fig, out / "histograms.png")


def _tornado(out: Path, result) -> Path | None:
    from flexrv.viz.plots import _plt, _save

    plt = _plt()
    rows = result["what_if"]["rows"]
    fig, ax = plt.subplots(figsize=(8, 0.45 * max(len(rows), 4) + 1.5))
    if rows and rows[0]["p95_te_pp_arcsec"] is not None:
        rows_up = rows[::-1]  # largest span on top
        names = [r["tolerance"] for r in rows_up]
        base = [r["p95_te_pp_arcsec"] or 0.0 for r in rows_up]
        lo = [(r["p95_te_pp_arcsec_halved"] or b) - b for r, b in zip(rows_up, base)]
        hi = [(r["p95_te_pp_arcsec_doubled"] or b) - b for r, b in zip(rows_up, base)]
        ax.barh(names, hi, color="C3", label="tolerance doubled")
        ax.barh(names, lo, color="C0", label="tolerance halved")
        ax.axvline(0.0, color="k", lw=1)
        ax.set_xlabel(
            f"change of P95 TE p-p [arcsec] (paired, up to {result['what_if']['samples']} re-evaluated samples per row)"
        )
        ax.legend(fontsize=8)
    else:
        ranking = result["ranked_sensitivities"].get("te_pp_arcsec", [])
        names = [r["tolerance"] for r in ranking][::-1]
        vals = [r.get("ST", r.get("src2", 0.0)) for r in ranking][::-1]
        ax.barh(names, vals, color="C0")
        ax.set_xlabel("sensitivity of TE p-p (" + (ranking[0]["method"] if ranking else "-") + ")")
    ax.set_title(f"tolerance study {result['design']}: which tolerance drives TE p-p")
    fig.tight_layout()
    return _save(fig, out / "tornado.png")


def _markdown(r: dict[str, Any]) -> str:
    lines = [
        f"# Tolerance study: {r['design']}",
        "",
        f"{r['samples']} samples ({r['sampler']}, seed {r['seed']}), {r['variables']} variables, "
        f"{r['evaluations']} evaluations ({r['failed']} failed), resolution {json.dumps(r['resolution'])}.",
        "",
        "| output | P50 | P95 | P99.7 | mean | std |",
        "|---|---|---|---|---|---|",
    ]
    for k, p in r["percentiles"].items():
        if p.get("n"):
            lines.append(
                f"| {k} | {p['P50']:.4g} | {p['P95']:.4g} | {p['P99.7']:.4g} | {p['mean']:.4g} | {p['std']:.3g} |"
            )
    y = r["yield"]
    if y and y["yield"] is not None:
        lines += [
            "",
            f"Yield ({', '.join(y['specs'])}): {y['passed']}/{y['n']} = {y['yield']:.3f}, "
            f"95 % Clopper-Pearson interval {y['ci_low']:.3f}..{y['ci_high']:.3f}.",
        ]
    lines += ["", "## Ranked sensitivities of TE p-p", ""]
    for row in r["ranked_sensitivities"].get("te_pp_arcsec", [])[:10]:
        val = (
            f"ST {row['ST']:.3f}, S1 {row['S1']:.3f}"
            if row["method"] == "sobol"
            else f"SRC^2 {row['src2']:.3f} ({row['method']}, R^2 {row['r2']:.2f})"
        )
        lines.append(f"- {row['tolerance']}: {val}")
    w = r["what_if"]
    if w["rows"]:
        lines += [
            "",
            f"## What if ({w['method']}; M = {w['samples']})",
            "",
            "| tolerance | samples | P95 TE p-p | halved | doubled | yield | halved | doubled |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for row in w["rows"]:
            f = lambda v: "-" if v is None else f"{v:.4g}"  # noqa: E731
            lines.append(
                f"| {row['tolerance']} | {row['samples_used']} | {f(row['p95_te_pp_arcsec'])} | "
                f"{f(row['p95_te_pp_arcsec_halved'])} | "
                f"{f(row['p95_te_pp_arcsec_doubled'])} | {f(row['yield'])} | {f(row['yield_halved'])} | "
                f"{f(row['yield_doubled'])} |"
            )
    return "\n".join(lines) + "\n"
