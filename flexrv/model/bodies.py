"""The elastic bodies condensed into the force elements: the design's switches
(:func:`with_bodies`) and the condensed FE matrices (:func:`body_compliance_matrix`),
each built only for the element that carries the body (the carrier's for the crank
supports, the discs' for the pins)."""

from __future__ import annotations

import numpy as np

#: elastic bodies condensed into the force elements of every model (rigid, balls, flexible)
BODY_PARTS = ("carrier", "cycloid_disc")


def body_compliance_matrix(reducer, body: str) -> np.ndarray:
    """The elastic body's condensed matrix, per the design's switch: ``"carrier"``: the
    (2N, 2N) support-point compliance [m/N] if ``carrier.body_model = "condensed_fe"`` (and
    the design has a ``[carrier]`` table), else (0, 0); ``"cycloid_disc"``: the discs'
    (n_discs, 3, 3) rim compliance if ``second_stage.disc_body_model = "condensed_fe"``, else
    (0, 3, 3). From the cached FE condensations (:mod:`flexrv.fem.carrier`,
    :mod:`flexrv.fem.disc`; built once per design, docs/benchmarks.md gives the cost).
    Functions of the design without its errors: shared by its error sets inside
    :func:`flexrv.design.manufacturing.shared_nominal_constants`."""
    from flexrv.design.manufacturing import nominal_shared

    if body not in BODY_PARTS:
        raise ValueError(f"body = {body!r}: choose one of {BODY_PARTS}")
    return nominal_shared(reducer, f"body_compliance_matrix:{body}", lambda r: _body_compliance_matrix(r, body))


def _body_compliance_matrix(reducer, body: str) -> np.ndarray:
    if body == "carrier":
        c = np.zeros((0, 0))
        cr = reducer.carrier
        if cr is not None and cr.body_model == "condensed_fe":
            from flexrv.fem.carrier import crank_support_compliance

            c = crank_support_compliance(reducer)
        return np.ascontiguousarray(c, dtype=float)
    c = np.zeros((0, 3, 3))
    if reducer.second_stage.disc_body_model == "condensed_fe":
        from flexrv.fem.disc import rim_compliance

        c = np.repeat(rim_compliance(reducer)[None], reducer.second_stage.n_discs, axis=0)
    return np.ascontiguousarray(c, dtype=float)


def with_bodies(reducer, bodies) -> object:
    """The design with its elastic-body switches set from ``bodies`` (names among
    ``carrier``, ``cycloid_disc``): a named body becomes ``condensed_fe``, an unnamed
    one ``rigid`` (the one parameter route of ``--parts``: the switches are design
    fields)."""
    bodies = set(bodies)
    ss = reducer.second_stage.model_copy(
        update={"disc_body_model": "condensed_fe" if "cycloid_disc" in bodies else "rigid"}
    )
    update = {"second_stage": ss}
    if reducer.carrier is not None:
        update["carrier"] = reducer.carrier.model_copy(
            update={"body_model": "condensed_fe" if "carrier" in bodies else "rigid"}
        )
    elif "carrier" in bodies:
        from flexrv.errors import ConfigError

        raise ConfigError("parts = carrier needs the design's [carrier] table (carrier geometry); this design has none")
    return reducer.model_copy(update=update)
