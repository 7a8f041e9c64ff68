"""The force elements' shared parts: the numerics (flexrv.model.numerics), the typed
kernel parameters (flexrv.model.core.params) and the rule that kernels read their
parameters by name."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "flexrv"

#: the positional pack readers the kernels used before their parameters were named: a
#: scalar vector read by number (``sc[3]``, ``sc[sc.shape[0] - 1]``, ``dc[1]``) or by an index
#: constant (``sc[SC_G]``, ``rigid[SC_K_BEND] = 0``: the support law's constants are a NamedTuple), a row
#: geometry or contact law read by number (``geometry[13]``, ``law_i[5]``), the housing's compliance
#: read from its state vector (``hs[0]``), a pack read
#: by position (``pack[0][-1]``, ``loads[1]``) or unpacked whole (``a, b, ... = pack``),
#: a hand-sized empty pack (``np.zeros(13)`` in ``empty_pack``)
_OLD_READERS = (
    r"\bsc\[\s*(\d|sc\.shape)",
    r"\[\s*SC_[A-Z_]+\s*\]",
    r"\bdc\[\s*\d",
    r"\bhs\[\s*0\s*\]",
    r"\bgeometry\[\s*\d",
    r"\blaw(_i|_o)?\[\s*(\d|N_LAW)",
    r"\bpack\[\s*-?\d",
    r"\bpacks?\[[^\]]*\]\[\s*-?\d",
    r"\bloads\[\s*1\s*\]",
    r"=\s*\(?\s*pack\s*\)?\s*$",
)


def _sources():
    """Every source of the package but the generated fused kernels and the kernel cache's
    bookkeeping (numba's own index tuples)."""
    return sorted(
        p
        for p in PACKAGE.rglob("*.py")
        if p.name != "kernel_cache.py" and "_generated" not in p.relative_to(PACKAGE).parts
    )


def test_no_positional_pack_reader_in_flexrv():
    """No kernel, contact law or analysis reads its parameters by position: every pattern
    of _OLD_READERS is absent from flexrv/ (a wrong index would compile and run; a wrong
    name fails to compile), and every ``empty_pack`` is derived from its pack type
    (flexrv.model.core.params.empty_pack), not sized by hand."""
    hits = []
    for path in _sources():
        text = path.read_text()
        for n, line in enumerate(text.splitlines(), 1):
            code = line.split("#", 1)[0]
            for pat in _OLD_READERS:
                if re.search(pat, code):
                    hits.append(f"{path.relative_to(PACKAGE)}:{n}: {line.strip()}")
        for m in re.finditer(r"def empty_pack\(\):\n((?:        .*\n|\n)+)", text):
            body = [s.strip() for s in m.group(1).splitlines() if s.strip()]
            if len(body) != 1 or not re.fullmatch(r"return empty_pack\(\w+\)", body[0]):
                hits.append(f"{path.relative_to(PACKAGE)}: empty_pack not derived: {body}")
    assert not hits, "\n".join(hits)


def test_old_reader_patterns_catch_the_old_code():
    """The patterns above are not vacuous: each flags a line of the kind it names."""
    samples = (
        "    z_rp, R_p = int(sc[0]), sc[1]",
        "    mu = sc[sc.shape[0] - 2]",
        "    kb, g = sc[SC_K_BEND], sc[SC_G]",
        "    rigid[SC_K_BEND] = 0.0",
        "    k = self.sc[SC_LINEAR]",
        "    cd, linear = dc[0], dc[1] > 0.5",
        "    ch = hs[0] if hs.shape[0] > 0 else 0.0",
        "    if geometry[13] > 0.0:",
        "    damping = max(law_i[5], law_o[5])",
        "        ctr = pack[0][-1]",
        '        pin_ctr = packs[index("pins")][0][-1]',
        "    load = loads[1]",
        "    idx, sc, beta0, planet, out_f, out_d, out_k = pack",
    )
    for s in samples:
        assert any(re.search(p, s) for p in _OLD_READERS), s


# ------------------------------------------------------------------ numerics
def test_small_dense_factorisations_match_numpy():
    """numerics.linalg: Cholesky factor and solve of an SPD matrix (cond ~1e4) against
    numpy.linalg.solve to 1e-12 relative times the condition number; the 3x3 adjugate
    gives det and the inverse to 1e-14 relative (numpy.linalg.det, inv); condensed_step
    equals (I + s C J)^-1 r to 1e-12 for both signs."""
    from flexrv.model.numerics.linalg import adjugate3, cholesky, cholesky_solve, condensed_step

    rng = np.random.default_rng(5)
    for m in (1, 3, 8):
        u, _ = np.linalg.qr(rng.normal(size=(m, m)))
        a = u @ np.diag(np.logspace(0, -4, m)) @ u.T
        b = rng.normal(size=m)
        lf = a.copy()
        cholesky(lf)
        x = b.copy()
        cholesky_solve(lf, x)
        ref = np.linalg.solve(a, b)
        assert np.abs(x - ref).max() <= 1e-12 * 1e4 * np.abs(ref).max()
    k = rng.normal(size=(3, 3)) + 3 * np.eye(3)
    adj = np.empty((3, 3))
    det = adjugate3(k, adj)
    assert det == pytest.approx(np.linalg.det(k), rel=1e-14)
    assert np.abs(adj / det - np.linalg.inv(k)).max() <= 1e-14 * np.abs(np.linalg.inv(k)).max()
    m = 6
    c, j, r = rng.normal(size=(m, m)) * 0.1, rng.normal(size=(m, m)), rng.normal(size=m)
    for sign in (1.0, -1.0):
        step, tmp, inv = np.empty(m), np.empty((m, m)), np.empty((m, m))
        condensed_step(c, j, sign, r, tmp, inv, step)
        ref = np.linalg.solve(np.eye(m) + sign * c @ j, r)
        assert np.abs(step - ref).max() <= 1e-12 * np.abs(ref).max()


def _solve_cubic_condensation(x_start, c, a, k, max_evals=80):
    """x = c F(x), F(x) = a - k x^3 (a scalar spring of compliance c against a cubic
    contact) with the shared Newton (sign -1: R = x - c F); returns (x, evaluations)."""
    from flexrv.model.numerics.newton import NEWTON_STATE, newton_start, newton_update

    x, x0, step, res = np.array([x_start]), np.zeros(1), np.zeros(1), np.zeros(1)
    cm, jm, tmp, inv = np.array([[c]]), np.zeros((1, 1)), np.zeros((1, 1)), np.zeros((1, 1))
    state = np.zeros(NEWTON_STATE)
    newton_start(state)
    n = 0
    while True:
        n += 1
        f = a - k * x[0] ** 3
        jm[0, 0] = -3.0 * k * x[0] ** 2
        res[0] = x[0] - c * f
        if newton_update(
            state, abs(res[0]), abs(x[0]), x, x0, step, res, cm, jm, -1.0, tmp, inv, max_evals, 80, 0.0, 100.0
        ):
            return x[0] - step[0], n


def test_shared_newton_solves_a_closed_form():
    """numerics.newton: the condensed body's Newton on x = c (a - k x^3) reaches the
    real root of c k x^3 + x - c a = 0 (Cardano, numpy.roots) to 1e-10 relative (its
    tolerance rule) from a near start in a few evaluations and from a far start
    (x0 = 50 x*); the evaluation cap stops it."""
    c, a, k = 2e-3, 5.0, 4e2
    roots = np.roots([c * k, 0.0, 1.0, -c * a])
    ref = float(roots[np.argmin(np.abs(roots.imag))].real)
    x, n = _solve_cubic_condensation(1.1 * ref, c, a, k)
    assert x == pytest.approx(ref, rel=1e-10) and n <= 6
    x, n = _solve_cubic_condensation(50.0 * ref, c, a, k)
    assert x == pytest.approx(ref, rel=1e-10) and n <= 80
    _, n = _solve_cubic_condensation(50.0 * ref, c, a, k, max_evals=3)
    assert n == 3


def test_predictor_is_trusted_within_a_tenth():
    """numerics.newton.apply_predictor: applied when the weighted change is <= 0.1 of
    the weighted size, refused above."""
    from flexrv.model.numerics.newton import apply_predictor

    w = np.array([1.0, 1.0, 10.0])
    x = np.array([1.0, -2.0, 0.1])
    assert apply_predictor(x, np.array([0.0, 0.19, 0.0]), w) and x[1] == -1.81
    assert not apply_predictor(x, np.array([0.0, 0.0, 0.05]), w) and x[2] == 0.1


# ------------------------------------------------------------------ typed parameters
def test_law_type_converts_and_rejects():
    """core.params.law_type: every field required, each converted to its declared type,
    unknown names refused with one message naming them."""
    from flexrv.model.core.params import law_type

    Law = law_type("Law", n=int, a=float, on=bool, table=np.ndarray)
    p = Law.of(n=3.0, a=np.float32(0.5), on=1, table=[1, 2])
    assert type(p.n) is int and type(p.a) is float and p.on is True and p.table.dtype == np.float64
    with pytest.raises(TypeError, match="missing \\['on'\\].*unknown \\['x'\\]"):
        Law.of(n=1, a=1.0, table=[], x=2)
    z = Law.zero()
    assert (z.n, z.a, z.on) == (0, 0.0, False) and type(z.n) is int and z.table.shape == (0,)


def test_parameter_types_pickle_by_reference():
    """Every registered element's pack type and law type is found again by name when
    unpickled (the same class object): numba's cache keys a compiled kernel on its
    argument types, and a type pickled by value is a new class in every process, so every
    kernel taking it would compile again in every run (measured: the fused kernel, ~6 min
    per process on the loaded 2-core machine, before the types named their module)."""
    import pickle

    import flexrv.model.kernels  # noqa: F401  (registers the built-in elements)
    from flexrv.model.bearing_kernel import PointLaw, RowGeometry
    from flexrv.model.core.registry import ELEMENTS

    types = [RowGeometry, PointLaw]
    for spec in ELEMENTS.values():
        mod = __import__(spec.group.__module__, fromlist=["_"])
        types += [v for v in vars(mod).values() if isinstance(v, type) and hasattr(v, "_kinds") or hasattr(v, "_types")]
    assert len(types) >= 12
    for cls in types:
        assert pickle.loads(pickle.dumps(cls)) is cls, cls


def test_empty_packs_have_the_live_packs_types():
    """An absent element's pack (derived from its pack type) has the numba type of a
    live pack of the same element on rv40e, so the fused kernel compiles once; every
    live pack matches its declared field kinds (core.params.check_pack)."""
    from numba import typeof

    from flexrv.design import load
    from flexrv.model.core.params import check_pack
    from flexrv.model.factory import build_model

    m = build_model(load("rv40e"), exudyn=False)
    checked = 0
    for g in m.groups:
        if not hasattr(type(g), "empty_pack"):
            continue
        live = g.pack(np.arange(m.n, dtype=np.int64)[: sum(m.members[x].n for x in g.members)])
        check_pack(live)
        assert typeof(type(g).empty_pack()) == typeof(live), g.name
        checked += 1
    assert checked >= 5
