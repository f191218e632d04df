"""The campaign stage (see README.md in this folder): Monte Carlo trials of a path under sampled wind.

Kept free of heavy imports: worker processes import this package before their thread limits are set.
"""
