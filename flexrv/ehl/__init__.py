"""Elastohydrodynamic lubrication of rolling contacts.

* :mod:`flexrv.ehl.film` — closed-form films (Hamrock–Dowson, Moes, Pan–Hamrock);
* :mod:`flexrv.ehl.solver` — numerical steady isothermal point-contact EHL
  (:func:`~flexrv.ehl.solver.solve_point_contact`);
* :mod:`flexrv.ehl.maps` — cached solver maps h_c(Q, u) for the contact law
  (:mod:`flexrv.contact.ehl_law`).

Submodules are imported on use (this package imports nothing eagerly, so that
``flexrv.contact`` and ``flexrv.ehl`` can import each other's modules freely).
"""
