"""The scored ship: a ship's true mesh with the oracle that judges captures of it, built once from a config.

The campaign's flight evaluator, the WRP optimiser's Table 3 error, the studies and the surrogate diagnostics
all score capture poses on "the configured ship with the configured oracle"; they build it here, once, and keep
it for every call (the ship's procedural mesh and the oracle's ground-truth sampling are the slow parts).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from wrp_eval.recon import make_oracle

SEED_MODULUS = 2**31 - 1      # the oracles' RNGs take 31-bit seeds; campaign seeds are 64-bit


@dataclass(frozen=True)
class ScoredShip:
    """particulars (ShipParticulars), mesh (the true ship, trimesh.Trimesh, metres) and oracle
    (:class:`wrp_eval.recon.base.Oracle`)."""

    particulars: object
    mesh: object
    oracle: object

    def score(self, captures, seed: int = 0):
        """The oracle's :class:`ReconResult` for ``captures`` (a CaptureSet); any int seed (reduced mod 2^31-1)."""
        return self.oracle.evaluate(captures, self.mesh, seed=int(seed) % SEED_MODULUS)


def scored_ship(config, config_dir: str | Path = ".", oracle_kind: str | None = None) -> ScoredShip:
    """The :class:`ScoredShip` of an ExperimentConfig: its ``ship:`` section resolved relative to ``config_dir``
    and the oracle of its ``oracle:`` section, of kind ``oracle_kind`` (default: ``campaign.oracle``, the one
    the campaign's flights are scored with)."""
    from wrp_eval.ship.resolve import resolve_ship_full
    ship = resolve_ship_full(config.ship, config_dir)
    oracle = make_oracle(config.oracle, oracle_kind or config.campaign.oracle)
    return ScoredShip(ship.particulars, ship.mesh, oracle)
