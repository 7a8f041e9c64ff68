"""Elastohydrodynamic lubrication of rolling contacts.

* :mod:`flexrv.ehl.film` — closed-form films (Hamrock–Dowson, Moes, Pan–Hamrock);
* :mod:`flexrv.ehl.solver` — numerical steady isothermal point-contact EHL
  (:func:`~flexrv.ehl.solver.solve_point_contact`);
* :mod:`flexrv.ehl.maps` — cached solver maps h_c(Q, u) for the contact law;
* :mod:`flexrv.ehl.law` — EHL-corrected normal contact laws (the film in series with the
  Hertz approach of :mod:`flexrv.contact.hertz`).

The package sits above :mod:`flexrv.contact` (``flexrv.LAYERS``): it uses the Hertz contact
laws, and nothing in ``contact`` imports it. Submodules are imported on use.
"""
