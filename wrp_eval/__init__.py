"""wrp-eval: wind-resistant UAV photo-flight planning around ships, evaluated by Monte Carlo flights in MuJoCo.

Stages (one sub-package each, meeting through small value types):
ship -> planning -> wind -> sim -> recon -> campaign -> surrogate -> wrp -> export.
"""

__version__ = "0.1.0"
