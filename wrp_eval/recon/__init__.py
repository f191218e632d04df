"""Reconstruction-quality oracles: capture poses + the true ship mesh -> error, completeness, failed?

``make_oracle(section, kind)`` gives the synthetic MVS oracle (default, campaign speed) or the pycolmap
photogrammetric one (validation; ``pip install .[photogrammetry]``). See README.md.
"""

from __future__ import annotations

from wrp_eval.recon.base import Oracle, ReconResult
from wrp_eval.recon.config import OracleSection


def make_oracle(section: OracleSection = OracleSection(), kind: str | None = None) -> Oracle:
    """The oracle named by ``kind`` (default ``section.kind``), configured by ``section``."""
    kind = kind or section.kind
    if kind == "synthetic":
        from wrp_eval.recon.synthetic import SyntheticOracle
        return SyntheticOracle(section)
    if kind == "colmap":
        from wrp_eval.recon.colmap import ColmapOracle
        return ColmapOracle(section)
    from wrp_eval.errors import InputError
    raise InputError("oracle", f"unknown oracle kind {kind!r}; choose synthetic or colmap")


__all__ = ["Oracle", "OracleSection", "ReconResult", "make_oracle"]
