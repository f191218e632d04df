"""The typed experiment context handed to the jobs: one validated config and everything derived from it once.

A job (``wrp-eval run``, ``campaign``, ``train``, ``optimize``, ``evaluate``, a study variant) receives an
:class:`ExperimentContext` instead of an untyped config and a loose ``config_dir``:

* ``config``: the :class:`~wrp_eval.config.ExperimentConfig`, validated once per process (:meth:`load`);
* ``config_dir``: the folder the config's relative files (AIS, mesh, netCDF, path) are resolved against;
* ``folders``: the run's output folders (:class:`RunFolders`, the one place ``logs/<run>/...`` is spelt);
* the seeds (:attr:`run_seed`, :attr:`campaign_seed`, :meth:`planning_rng`);
* the resolved ship, the scored ship (mesh + oracle) and the planned path, each built on first use and kept.

The context sits above the stages it resolves (ship, planning, recon) and below the jobs that take it
(campaign, surrogate, wrp, study, pipeline): see the import contract in .importlinter.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from wrp_eval.config import ExperimentConfig, TrialConfig, load_experiment
from wrp_eval.planning.path import FlightPath
from wrp_eval.planning.planner import PlanResult, plan, planning_rng
from wrp_eval.recon.scored_ship import ScoredShip, make_oracle
from wrp_eval.ship.particulars import ShipParticulars
from wrp_eval.ship.proxy import Proxy, build_proxy
from wrp_eval.ship.resolve import ResolvedShip, resolve_particulars, resolve_ship_full

LOGS_DIR = Path("logs")


@dataclass(frozen=True)
class RunFolders:
    """Where a run writes: ``root`` = logs/<run.name>; each stage's folder honours its section's override.

    plan/, campaign/, surrogate/, evaluate/ (with wrp-<kind>/ and campaign-<path>/ inside), wrp-<kind>/ (the
    ``optimize`` command alone), missions/, study/, envelope/; ship.rrd, plan.rrd, run.rrd, report.md, run_summary.json.
    """

    root: Path
    campaign: Path
    surrogate: Path
    evaluate: Path
    envelope: Path
    wrp_out: Path | None = None

    @classmethod
    def of(cls, config: ExperimentConfig) -> "RunFolders":
        root = LOGS_DIR / config.run.name
        return cls(root=root,
                   campaign=Path(config.campaign.outputs.dir or root / "campaign"),
                   surrogate=Path(config.surrogate.out_dir or root / "surrogate"),
                   evaluate=Path(config.wrp.evaluate.out_dir or root / "evaluate"),
                   envelope=Path(config.envelope.out_dir or root / "envelope"),
                   wrp_out=Path(config.wrp.out_dir) if config.wrp.out_dir else None)

    @property
    def plan(self) -> Path:
        return self.root / "plan"

    @property
    def missions(self) -> Path:
        return self.root / "missions"

    @property
    def study(self) -> Path:
        return self.root / "study"

    @property
    def recording(self) -> Path:
        """The run's merged rerun recording."""
        return self.root / "run.rrd"

    def wrp(self, kind: str) -> Path:
        """The ``optimize`` command's folder for ``kind`` ("iswrp" | "swrp")."""
        return self.wrp_out or self.root / f"wrp-{kind}"

    def evaluated_wrp(self, kind: str) -> Path:
        """The WRP ``evaluate`` optimises (inside the run's evaluate folder)."""
        return evaluated_wrp_dir(self.evaluate, kind)


def evaluated_wrp_dir(evaluate_dir: Path, kind: str) -> Path:
    """The folder of the ``kind`` ("iswrp" | "swrp") WRP inside an ``evaluate`` folder."""
    return Path(evaluate_dir) / f"wrp-{kind}"


def evaluated_campaign_dir(evaluate_dir: Path, name: str) -> Path:
    """The campaign folder of path ``name`` ("initial" | "iswrp" | "swrp") inside an ``evaluate`` folder."""
    return Path(evaluate_dir) / f"campaign-{name}"


@dataclass
class ExperimentContext:
    """One experiment: the validated config, its folder and what is resolved from it once (see module doc).

    ``source``: how the config is named in messages (its file, or a study variant)."""

    config: ExperimentConfig
    config_dir: Path = Path(".")
    source: str = "config"
    folders: RunFolders = field(init=False)

    def __post_init__(self) -> None:
        self.config_dir = Path(self.config_dir)
        self.folders = RunFolders.of(self.config)

    @classmethod
    def load(cls, config_file: str | Path) -> "ExperimentContext":
        """Read and validate the config file (the one validation of this process)."""
        file = Path(config_file)
        return cls(load_experiment(file), file.parent, str(file))

    def with_config(self, config: ExperimentConfig, source: str | None = None) -> "ExperimentContext":
        """The context of another (already validated) config in the same folder: a study variant."""
        return ExperimentContext(config, self.config_dir, source or self.source)

    def reuse_from(self, other: "ExperimentContext") -> None:
        """Take what ``other`` has already resolved where this config would resolve the same (the same config
        folder and name, and the same sections it is built from): the ship, its particulars and flight proxy
        (``ship:``), its plan (``ship:``, ``planning:``, ``run.seed``; its metrics keep the planning time of the
        context that planned it) and the scored ship (``ship:``, ``oracle:``, ``campaign.oracle``). A study's
        variants mostly differ in other sections, and each would otherwise plan and score the same ship again."""
        if (other.config_dir, other.source) != (self.config_dir, self.source):
            return
        a, b = self.config, other.config
        same_ship = a.ship == b.ship
        shared = {"ship": same_ship, "particulars_with_provenance": same_ship, "flight_proxy": same_ship,
                  "planned": same_ship and a.planning == b.planning and a.run.seed == b.run.seed,
                  "scored_ship": same_ship and a.oracle == b.oracle and a.campaign.oracle == b.campaign.oracle}
        for name, same in shared.items():      # the cached_property values other has computed
            if same and name in other.__dict__ and name not in self.__dict__:
                self.__dict__[name] = other.__dict__[name]

    # seeds --------------------------------------------------------------------------------------------
    @property
    def run_seed(self) -> int:
        return self.config.run.seed

    @property
    def campaign_seed(self) -> int:
        """The root of every trial's draws: ``campaign.seed``, else ``run.seed``."""
        seed = self.config.campaign.seed
        return seed if seed is not None else self.config.run.seed

    def planning_rng(self) -> np.random.Generator:
        return planning_rng(self.config.run.seed)

    # the campaign's view of the config ----------------------------------------------------------------
    @property
    def trial_config(self) -> TrialConfig:
        """The sections a trial reads (see :meth:`ExperimentConfig.trial_config`)."""
        return self.config.trial_config()

    @property
    def training_campaign_dir(self) -> Path:
        """The campaign the surrogate learns from: ``surrogate.campaign_dir``, else the campaign's folder."""
        given = self.config.surrogate.campaign_dir
        return Path(given) if given is not None else self.folders.campaign

    # resolved once ------------------------------------------------------------------------------------
    @cached_property
    def ship(self) -> ResolvedShip:
        """Particulars, proxy, mesh and surface complexity of the ``ship:`` section."""
        return resolve_ship_full(self.config.ship, self.config_dir, self.source)

    @cached_property
    def particulars_with_provenance(self) -> tuple[ShipParticulars, dict[str, str]]:
        """The ship's particulars alone (no mesh is built) and where each field came from."""
        if "ship" in self.__dict__:
            return self.ship.particulars, self.ship.provenance
        return resolve_particulars(self.config.ship, self.config_dir, self.source)

    @property
    def particulars(self) -> ShipParticulars:
        return self.particulars_with_provenance[0]

    @cached_property
    def flight_proxy(self) -> Proxy:
        """The proxy whose no-fly box flights must respect (``ship.no_fly_margin_m``, no height error): the box
        the WRP's moved viewpoints and the exported missions are checked against."""
        return build_proxy(self.particulars, self.config.ship.no_fly_margin_m)

    @cached_property
    def scored_ship(self) -> ScoredShip:
        """The true ship mesh with the campaign's oracle (``campaign.oracle``)."""
        return self.scorer(self.config.campaign.oracle)

    def scorer(self, oracle_kind: str) -> ScoredShip:
        """The true ship mesh with the oracle ``oracle_kind`` ("synthetic" | "colmap") of ``oracle:``."""
        return ScoredShip(self.ship.particulars, self.ship.mesh, make_oracle(self.config.oracle, oracle_kind))

    @cached_property
    def planned(self) -> PlanResult:
        """The ``planning:`` section's plan of the ship, seeded by the planning stream of ``run.seed``; the
        path's metadata name the config and the seed."""
        result = plan(self.ship.proxy, self.ship.complexity.complexity, self.config.planning, self.planning_rng())
        meta = {**result.path.metadata, "config": self.source, "seed": self.run_seed}
        return dataclasses.replace(result, path=dataclasses.replace(result.path, metadata=meta))

    def plan_with(self, method: str) -> PlanResult:
        """The plan of the ship by another ``planning.method`` (same seed stream), unchanged metadata."""
        section = self.config.planning.model_copy(update={"method": method})
        return plan(self.ship.proxy, self.ship.complexity.complexity, section, self.planning_rng())

    @cached_property
    def campaign_path(self) -> FlightPath:
        """The path the campaign flies: ``campaign.path`` (relative to the config's folder) or the plan."""
        given = self.config.campaign.path
        if given is None:
            return self.planned.path
        file = Path(given)
        if not file.is_absolute() and not file.exists():
            file = self.config_dir / file
        return FlightPath.load(file)

