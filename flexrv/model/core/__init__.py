"""The model's core: typed kernel parameters (:mod:`~flexrv.model.core.params`)."""
