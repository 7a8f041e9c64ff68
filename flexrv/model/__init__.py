"""Exudyn assembly of reducer models.

``flexrv.model.factory.build_model(reducer, "rigid")`` assembles the rigid-member
model with compliant contacts: members (carrier with its 5-DOF main-bearing
element, cranks = planets, cycloid discs) as ``NodeGenericODE2`` nodes with
constant mass matrices, and the force elements, the compiled ones registered in
:mod:`.core.registry` and evaluated in ONE generated fused kernel (:mod:`.kernels`), each building its own
typed parameters from the design (the element's ``parameters(reducer, drive)``; the
shared ones in :mod:`.drive`), their kernel packs typed and read by name
(:mod:`.core.params`), their shared numerics in :mod:`.numerics`:

* :mod:`.gear_stage` — sun–planet meshes along the line of action (time-varying
  ISO 6336 stiffness, damping, backlash; the sun angle is prescribed by the drive);
* :mod:`.cranks_discs` — crank support bearings in the carrier; needle bearings
  (:cite:`seed004` empirical law or roller-resolved Hertz line contacts, :cite:`seed003`);
* :mod:`.pins` — every pin–disc contact (exact gap to the modified profile);
* :mod:`.main_bearing_rigid` — linear carrier bearing (the flexible model
  replaces it, :mod:`.flexible_bearing`);
* :mod:`.loads` — seed drive (input speed step) and load torque step.

Why TE appears and how it is built is explained in :mod:`flexrv.post.results`;
the planar-DOF choice is justified in :mod:`.drive`.
"""
