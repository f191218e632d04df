"""Reconstruction-quality oracles: capture poses + the true ship mesh -> error, completeness, failed?

``make_oracle(section, kind)`` gives the synthetic MVS oracle (default, campaign speed) or the pycolmap
photogrammetric one (validation; ``pip install .[photogrammetry]``). See README.md.
"""

from __future__ import annotations

# base (open3d) is imported only when an oracle is made: the config and the CLI import this package, and
# open3d costs ~1 s at every start-up and worker spawn.


def make_oracle(section=None, kind: str | None = None):
    """The oracle (:class:`wrp_eval.recon.base.Oracle`) named by ``kind`` (default ``section.kind``),
    configured by ``section`` (an :class:`wrp_eval.recon.config.OracleSection`; default its defaults)."""
    from wrp_eval.recon.config import OracleSection
    section = OracleSection() if section is None else section
    kind = kind or section.kind
    if kind == "synthetic":
        from wrp_eval.recon.synthetic import SyntheticOracle
        return SyntheticOracle(section)
    if kind == "colmap":
        from wrp_eval.recon.colmap import ColmapOracle
        return ColmapOracle(section)
    from wrp_eval.errors import InputError
    raise InputError("oracle", f"unknown oracle kind {kind!r}; choose synthetic or colmap")


__all__ = ["make_oracle"]
