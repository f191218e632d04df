"""The surrogate stage (see README.md in this folder): a torch 1-D CNN from the per-viewpoint offsets of a
flown path (dx, dy, dz m, dyaw rad; shape (batch, n_views, 4)) to the oracle's reconstruction error, trained
on a campaign's trial store (paper Sec. 4.1, "fit function of UAV offset and reconstruction error").

Kept free of heavy imports: torch is imported by the modules that need it (model, train).
"""
