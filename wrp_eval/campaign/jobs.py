"""The campaign job of an experiment: its trial config, path, seed and folder taken from the context.

``wrp-eval campaign`` and ``wrp-eval run`` call :func:`campaign_job`; callers that fly another path or another
campaign section (``evaluate``, the studies) call :func:`wrp_eval.campaign.runner.run_campaign` directly.
"""

from __future__ import annotations

import logging
from dataclasses import replace
from pathlib import Path

from wrp_eval.campaign.evaluators import DEFAULT_EVALUATOR
from wrp_eval.campaign.runner import CampaignSummary, run_campaign, with_overrides
from wrp_eval.campaign.turbulence import turbulence_ratios, turbulence_stress_note
from wrp_eval.experiment import ExperimentContext
from wrp_eval.planning.path import FlightPath

log = logging.getLogger(__name__)


def campaign_job(ctx: ExperimentContext, *, out_dir: str | Path | None = None, n_trials: int | None = None,
                 backend: str | None = None, workers: int | None = None, rerun: bool | None = None,
                 evaluator: str = DEFAULT_EVALUATOR, evaluator_options: dict | None = None,
                 path: FlightPath | None = None) -> CampaignSummary:
    """Run (or resume) the experiment's campaign: ``campaign.path`` or the plan, flown ``campaign.n_trials``
    times from root seed ``campaign.seed`` (else ``run.seed``) into ``out_dir`` (default the run's campaign
    folder); the keyword overrides are the command line's. ``path``: fly this path instead (``wrp-eval run``
    flies the plan it has just written). A turbulence preset stronger than the drawn winds imply is reported in
    one line (printed, and in the summary's ``stress_note``)."""
    trial = with_overrides(ctx.trial_config, n_trials=n_trials, backend=backend, workers=workers, rerun=rerun)
    mesh = ctx.ship.mesh if trial.campaign.outputs.rerun else None
    out = Path(out_dir) if out_dir is not None else ctx.folders.campaign
    note = turbulence_stress_note(turbulence_ratios(trial.wind, trial.campaign, ctx.campaign_seed,
                                                    trial.campaign.n_trials, ctx.ship.particulars, ctx.config_dir))
    if note:
        log.info(f"[wrp-eval campaign] {note}")
    summary = run_campaign(trial, path if path is not None else ctx.campaign_path, out, root_seed=ctx.campaign_seed,
                           config_dir=ctx.config_dir, evaluator=evaluator, evaluator_options=evaluator_options,
                           ship_mesh=mesh)
    return replace(summary, stress_note=note)
