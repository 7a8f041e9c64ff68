"""Studies built on the models: many evaluations of a design (tolerance analysis, rigid vs
flexible comparison)."""
