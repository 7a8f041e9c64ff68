"""Shared compiled numerics of the model's force elements.

* :mod:`~flexrv.model.numerics.linalg`: small dense linear algebra without
  allocation or LAPACK (inverse, product, Cholesky, 3x3 adjugate, the condensed
  Newton correction);
* :mod:`~flexrv.model.numerics.newton`: the one damped predictor-Newton of the
  condensed (massless elastic) bodies: the discs' rims with the housing
  (:mod:`flexrv.model.pins`) and the carrier's support points
  (:mod:`flexrv.model.cranks_discs`).
"""
