"""The scored ship: a ship's true mesh with the oracle that judges captures of it, built once from a config.

The campaign's flight evaluator, the WRP optimiser's Table 3 error, the studies and the surrogate diagnostics
all score capture poses on "the configured ship with the configured oracle"; they build it here, once, and keep
it for every call (the ship's procedural mesh and the oracle's ground-truth sampling are the slow parts).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import trimesh

from wrp_eval.errors import InputError
from wrp_eval.recon.colmap import ColmapOracle
from wrp_eval.recon.config import OracleSection
from wrp_eval.recon.coverage import ViewCoverage, view_coverage
from wrp_eval.recon.oracle import MeshOracle
from wrp_eval.recon.synthetic import SyntheticOracle
from wrp_eval.ship.config import ShipSection
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.ship.resolve import resolve_ship_full

SEED_MODULUS = 2**31 - 1      # the oracles' RNGs take 31-bit seeds; campaign seeds are 64-bit


def make_oracle(section=None, kind: str | None = None) -> MeshOracle:
    """The oracle (:class:`wrp_eval.recon.oracle.Oracle`) named by ``kind`` (default ``section.kind``),
    configured by ``section`` (an :class:`wrp_eval.recon.config.OracleSection`; default its defaults)."""
    section = OracleSection() if section is None else section
    kind = kind or section.kind
    if kind == "synthetic":
        return SyntheticOracle(section)
    if kind == "colmap":
        return ColmapOracle(section)
    raise InputError("oracle", f"unknown oracle kind {kind!r}; choose synthetic or colmap")


@dataclass(frozen=True)
class ScoredShip:
    """particulars (ShipParticulars), mesh (the true ship, trimesh.Trimesh, metres) and oracle
    (:class:`wrp_eval.recon.oracle.Oracle`)."""

    particulars: ShipParticulars
    mesh: trimesh.Trimesh
    oracle: MeshOracle

    def score(self, captures, seed: int = 0):
        """The oracle's :class:`ReconResult` for ``captures`` (a CaptureSet); any int seed (reduced mod 2^31-1)."""
        return self.oracle.evaluate(captures, self.mesh, seed=int(seed) % SEED_MODULUS)

    def coverage(self, captures) -> ViewCoverage:
        """What each view of ``captures`` sees of this ship (:func:`wrp_eval.recon.coverage.view_coverage`)."""
        return view_coverage(captures, self.oracle.ground_truth(self.mesh), self.oracle.section)


def scored_ship(ship: ShipSection, oracle: OracleSection, oracle_kind: str,
                config_dir: str | Path = ".") -> ScoredShip:
    """The :class:`ScoredShip` of a ``ship:`` section resolved relative to ``config_dir`` with the oracle
    ``oracle_kind`` ("synthetic" | "colmap"; the campaign scores with ``campaign.oracle``) of an ``oracle:``
    section."""
    resolved = resolve_ship_full(ship, config_dir)
    return ScoredShip(resolved.particulars, resolved.mesh, make_oracle(oracle, oracle_kind))
