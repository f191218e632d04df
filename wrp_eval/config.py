"""Pydantic models of the YAML configs.

Each stage defines the model of its own section (``wrp_eval/<stage>/config.py``); this module composes
them into :class:`ExperimentConfig`, the one document ``wrp-eval run CONFIG`` and the stage commands read.
Unknown keys, wrong types and impossible values are refused with one line (see :mod:`wrp_eval.schema`).
"""

from __future__ import annotations

from pathlib import Path

from pydantic import Field

from wrp_eval.campaign.config import CampaignSection, TrialConfig
from wrp_eval.envelope.config import EnvelopeSection
from wrp_eval.export.config import ExportSection
from wrp_eval.planning.config import PlanningSection
from wrp_eval.recon.config import OracleSection
from wrp_eval.schema import StrictModel, load_model
from wrp_eval.ship.config import ShipSection
from wrp_eval.sim.config import SimSection
from wrp_eval.study.config import StudySection
from wrp_eval.surrogate.config import SurrogateSection
from wrp_eval.wind.config import WindSection
from wrp_eval.wrp.config import WrpSection


class RunSection(StrictModel):
    """Run-wide settings."""

    name: str = Field("quickstart", min_length=1, pattern=r"^[A-Za-z0-9_.-]+$",
                      description="run name: outputs go to logs/<name>/")
    seed: int = Field(0, ge=0, description="root seed of every random draw")


class ExperimentConfig(StrictModel):
    """A whole experiment. Every section has embedded defaults, so ``{}`` is a valid config."""

    run: RunSection = RunSection()
    ship: ShipSection = ShipSection()
    planning: PlanningSection = PlanningSection()
    wind: WindSection = WindSection()
    sim: SimSection = SimSection()
    campaign: CampaignSection = CampaignSection()
    oracle: OracleSection = OracleSection()
    surrogate: SurrogateSection = SurrogateSection()
    wrp: WrpSection = WrpSection()
    export: ExportSection = ExportSection()
    envelope: EnvelopeSection = EnvelopeSection()
    study: StudySection | None = Field(None, description="variants of this config measured side by side "
                                       "(the paper's tables, experiments/paper/); none: the single pipeline")

    def trial_config(self) -> TrialConfig:
        """The sections one campaign trial reads (ship, wind, sim, oracle, campaign), taken from this already
        validated config without validating them again."""
        return TrialConfig.model_construct(ship=self.ship, wind=self.wind, sim=self.sim, oracle=self.oracle,
                                           campaign=self.campaign)


def load_experiment(path: str | Path) -> ExperimentConfig:
    """Load and validate an experiment YAML file (raises :class:`InputError`)."""
    return load_model(ExperimentConfig, path)
