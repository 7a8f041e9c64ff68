"""The stiffness budget: the torsional compliance at the output split into the elements of
the torque path, in series. One function, :func:`stiffness_budget`, for every route:

* ``flexrv design`` (analytic): the element laws of :mod:`flexrv.analysis.torsional`
  (:func:`flexrv.analysis.torsional.stiffness_budget`) and the closed forms of
  :mod:`flexrv.analysis.path_compliances` (carrier joints, support-bearing rings, crank
  torsion, planet spline);
* ``flexrv te`` and ``flexrv stiffness-test`` (model routes): a model's strain-energy shares
  times its tangent compliance (:class:`ModelShares`). The models carry every element: the
  carrier's share splits into the carrier body, the support-bearing rings and the carrier
  joints by their strain energies (:meth:`flexrv.model.quasi_static.StaticModel.
  compliance_budget`), the gear stage's into the mesh, the crank torsion and the planet spline
  in proportion to their compliances along the line of action (:func:`split_gear_stage`);
* the measured-data path: the analytic budget with a measured rigidity beside it
  (``reference``), the difference being what the budget does not explain.

The budget is pure (the caller passes FE compliances and model shares); it is stored as an
:class:`xarray.Dataset` over the dimension ``budget_element`` (:meth:`Budget.to_dataset`,
:func:`budget_from_dataset`). Elements are named by what they are (:data:`ELEMENTS`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from flexrv.units import ARCSEC_PER_RAD, RAD_PER_ARCMIN

#: element name -> what it is (the budget's elements; a model's force group maps by :data:`GROUP_ELEMENT`)
ELEMENTS: dict[str, str] = {
    "pin_disc_contacts": "line contacts between the cycloid discs and the pins",
    "pin_seats": "line contacts between the pins and their housing grooves",
    "pin_bending": "bending of the pins over an unsupported span",
    "needle_bearings": "needle bearings between the crank eccentrics and the discs",
    "support_bearing_rollers": "roller-raceway contacts of the crank support bearings",
    "support_bearing_rings": "bending of the support bearings' cups and cones as thin rings",
    "crank_bending": "bending of the crank shafts between their supports",
    "crank_torsion": "torsion of the crank shafts between the planet spline and the eccentrics",
    "planet_spline": "the spline between a planet gear and its crank shaft",
    "carrier_body": "elastic carrier (plates and pillars, FE condensation)",
    "carrier_joints": "bolted and pinned joints between the carrier's pillars and its plate",
    "cycloid_disc_bodies": "elastic cycloid discs (FE condensation)",
    "pin_housing": "pin housing ring and tube (thin-ring estimate)",
    "first_stage_mesh": "involute mesh of the first stage, referred to the output",
    "main_bearing": "main bearing (ball model)",
    "crank_elasticity": "elastic crank shafts (flexible-crank model)",
}

#: a model's force group or an analytic law's key -> the budget element it is
GROUP_ELEMENT = {
    "pins": "pin_disc_contacts",
    "support_bearings": "support_bearing_rollers",
    "housing": "pin_housing",
    "carrier": "carrier_body",
    "cycloid_disc": "cycloid_disc_bodies",
    "gear_stage": "first_stage_mesh",
    "crankshaft_elasticity": "crank_elasticity",
}


@dataclass(frozen=True)
class ModelShares:
    """A model's budget: ``shares`` force group -> strain-energy fraction of the tangent
    compliance ``tangent_compliance`` [rad/(N m)] (:meth:`flexrv.model.quasi_static.
    StaticModel.compliance_budget`), ``bending_fraction`` the crank bending's part of the
    crank-support group (output ``crank_bending_fraction``)."""

    shares: dict
    tangent_compliance: float
    bending_fraction: float = 0.0


@dataclass(frozen=True)
class Budget:
    """A stiffness budget (SI). ``compliances``: element -> torsional compliance at the
    output [rad/(N m)] of the route's model (:data:`ELEMENTS`); ``reference``: named
    rigidities beside the budget [N m/rad] (e.g. the loop's measured ``rigidity_slope_50_100``)."""

    route: str
    torque: float
    compliances: dict
    notes: tuple = ()
    reference: dict = field(default_factory=dict)

    @property
    def elements(self) -> dict:
        return dict(self.compliances)

    @property
    def total(self) -> float:
        return float(sum(self.compliances.values()))

    @property
    def rigidity(self) -> float:
        """1 / total [N m/rad]."""
        return 1.0 / self.total

    def to_dict(self) -> dict:
        """Engineering units (what the commands print and ``--json`` carries): per element
        its compliance [arcsec/(N m)] and share [%]; the total and the rigidity [N m/arcmin]."""
        total = self.total
        out = {
            "route": self.route,
            "torque_Nm": self.torque,
            "elements": {
                k: {"compliance_arcsec_per_Nm": v * ARCSEC_PER_RAD, "share_percent": 100.0 * v / total}
                for k, v in self.compliances.items()
            },
            "total_compliance_arcsec_per_Nm": total * ARCSEC_PER_RAD,
            "rigidity_Nm_per_arcmin": RAD_PER_ARCMIN / total,
        }
        for name, k in self.reference.items():
            out[f"{name}_Nm_per_arcmin"] = k * RAD_PER_ARCMIN
        if self.notes:
            out["notes"] = list(self.notes)
        return out

    def to_dataset(self):
        """The budget as an :class:`xarray.Dataset` over ``budget_element``: ``budget_compliance``
        [arcsec/(N m)], ``budget_share`` [%]; the references as
        scalars ``budget_reference_<name>`` [N m/arcmin]; route, torque and notes as attributes."""
        import xarray as xr

        names = list(self.compliances)
        total = self.total
        c = np.array([self.compliances[k] for k in names])
        ds = xr.Dataset(
            {
                "budget_compliance": (
                    ("budget_element",),
                    c * ARCSEC_PER_RAD,
                    {"units": "arcsec/(N m)", "long_name": "torsional compliance at the output"},
                ),
                "budget_share": (("budget_element",), 100.0 * c / total, {"units": "%", "long_name": "share"}),
            },
            coords={"budget_element": ("budget_element", names)},
        )
        for name, k in self.reference.items():
            ds[f"budget_reference_{name}"] = ((), k * RAD_PER_ARCMIN, {"units": "N m/arcmin", "long_name": name})
        ds.attrs.update(
            {"budget_route": self.route, "budget_torque_Nm": self.torque, "budget_notes": "\n".join(self.notes)}
        )
        return ds

    def merged_into(self, ds):
        """``ds`` (a results dataset) with this budget's variables and attributes added."""
        b = self.to_dataset()
        out = ds.assign(**{k: b[k] for k in b.data_vars})
        out.attrs.update(b.attrs)
        return out


def budget_from_dataset(ds) -> Budget:
    """The :class:`Budget` stored by :meth:`Budget.to_dataset` (in a results dataset)."""
    names = [str(x) for x in ds["budget_element"].values]
    c = ds["budget_compliance"].values / ARCSEC_PER_RAD
    ref = {
        k[len("budget_reference_") :]: float(ds[k]) / RAD_PER_ARCMIN
        for k in ds.data_vars
        if k.startswith("budget_reference_")
    }
    notes = ds.attrs.get("budget_notes", "")
    return Budget(
        route=str(ds.attrs["budget_route"]),
        torque=float(ds.attrs["budget_torque_Nm"]),
        compliances={n: float(v) for n, v in zip(names, c)},
        notes=tuple(notes.split("\n")) if notes else (),
        reference=ref,
    )


def _named(compliances: dict) -> dict:
    return {GROUP_ELEMENT.get(k, k): v for k, v in compliances.items()}


def split_gear_stage(shares: dict, reducer) -> dict:
    """``shares`` with the gear stage's (``gear_stage``) split into the mesh, the crank torsion
    and the planet spline in proportion to their compliances in series along the line of
    action (:mod:`flexrv.model.gear_stage`): the mean mesh compliance 1 / k12
    (:func:`flexrv.analysis.mesh_stiffness.involute_stage`) and c r_bp^2 of each torsion
    (:func:`flexrv.analysis.path_compliances.model_compliances`). Proportional is exact for a
    constant mesh stiffness; the time-varying mesh moves only the mesh's own small part. With
    flexible cranks (a ``crankshaft_elasticity`` share) the crank's torsion is that group's and
    the gear stage keeps the spline only."""
    from flexrv.analysis.mesh_stiffness import involute_stage
    from flexrv.analysis.path_compliances import model_compliances

    frac = shares.get("gear_stage", 0.0)
    n = reducer.first_stage.n_planets
    mc = model_compliances(reducer, np.zeros((n, 2)))
    crank = 0.0 if "crankshaft_elasticity" in shares else mc.crank_torsion
    if frac <= 0.0 or crank + mc.planet_spline == 0.0:
        return dict(shares)
    stage = involute_stage(reducer)
    parts = {
        "gear_stage": 1.0 / stage.k12,
        "crank_torsion": crank * stage.rb_planet**2,
        "planet_spline": mc.planet_spline * stage.rb_planet**2,
    }
    total = sum(parts.values())
    out = dict(shares)
    out.update({k: frac * v / total for k, v in parts.items() if v > 0.0})
    return out


def stiffness_budget(
    reducer,
    torque: float | None = None,
    *,
    model: ModelShares | None = None,
    bodies: dict | None = None,
    reference: dict | None = None,
    route: str | None = None,
) -> Budget:
    """The stiffness budget of ``reducer`` at the output ``torque`` [N m] (default rated).

    Without ``model``: the analytic budget (:func:`flexrv.analysis.torsional.stiffness_budget`
    with the elastic bodies' compliances ``bodies`` {"carrier", "cycloid_disc"} [rad/(N m)])
    and the closed forms of :func:`flexrv.analysis.path_compliances.output_compliances`. With
    ``model`` (:class:`ModelShares`): the model's shares mapped to the elements
    (:func:`split_gear_stage`, :func:`flexrv.analysis.torsional.budget_from_group_shares`).
    ``reference``: named rigidities [N m/rad] stored beside the budget (a measured or
    simulated loop's)."""
    from flexrv.analysis import path_compliances
    from flexrv.analysis import torsional as tor

    t = reducer.operating.rated_torque_Nm if torque is None else float(torque)
    if model is None:
        b = tor.stiffness_budget(reducer, t, bodies=bodies)
        comp = _named(b.compliances)
        comp.update(path_compliances.output_compliances(reducer))
        return Budget(route or "analytic", t, comp, tuple(b.notes), dict(reference or {}))
    comp, notes = tor.budget_from_group_shares(
        split_gear_stage(model.shares, reducer), model.tangent_compliance, model.bending_fraction, reducer, t
    )
    return Budget(route or "model", t, _named(comp), tuple(notes), dict(reference or {}))
