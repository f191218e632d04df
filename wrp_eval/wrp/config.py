"""The ``wrp:`` section of an experiment config: the interval optimisation (paper Alg. 3 / 4) and the
robustness evaluation. Angles in degrees here (the edge of the system)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, field_validator

from wrp_eval.schema import StrictModel


class EvaluateSection(StrictModel):
    """``wrp-eval evaluate``: the initial path, ISWRP and SWRP flown as campaigns with the same config and root
    seed (so trial k of every path sees the same wind: common random numbers)."""

    n_trials: int = Field(100, ge=2, le=1_000_000)
    kinds: list[Literal["iswrp", "swrp"]] = Field(["iswrp", "swrp"], description="the paper's WRPs optimised and "
                                                  "flown ([]: none, and no surrogate is needed: the initial path "
                                                  "beside the flown levers, robust / direction / capture_stops)")
    thresholds_m: list[float] | None = Field(None, description="one threshold per WRP kind [iswrp, swrp] "
                                             "(none: the optimisation's threshold for both)")
    bootstrap: int = Field(2000, ge=100, le=1_000_000, description="bootstrap resamples of the CIs")
    placebos: int = Field(20, ge=0, le=10_000, description="placebo paths per WRP (as many viewpoints moved by "
                          "the same magnitudes, chosen at random), flown under the same winds: the control a "
                          "WRP's robustness gain must beat (0: no control, so no WRP is recommended)")
    spec_error_m: float | None = Field(None, gt=0, description="reconstruction spec: error at most this (m; none: "
                                       "1.1 x the initial path's wind-free error)")
    spec_completeness: float = Field(0.95, ge=0, le=1, description="reconstruction spec: completeness at least "
                                     "this")
    confidence: float = Field(0.95, gt=0.5, lt=1)
    forecast_trials: int = Field(64, ge=0, le=1_000_000, description="flights of the recommended path in the "
                                 "forecast wind (the wind: section's speed and direction): the operator's "
                                 "P(meets spec) with its CI and the go / no-go (0: none)")
    go_probability: float = Field(0.8, gt=0, le=1, description="GO when the lower confidence bound of P(meets "
                                  "spec) in the forecast wind reaches this")
    robust: bool = Field(False, description="also optimise and fly the robust kind (wrp.robust) and, when it "
                         "applied a lever, its placebos: the same levers at as many viewpoints chosen at random")
    direction: bool = Field(False, description="also fly the initial tour reversed (the same viewpoints the other "
                            "way round) and its placebos: the initial tour flown again in the same weather with its "
                            "flights' own errors drawn again (wrp/direction.py)")
    capture_stops: bool = Field(False, description="also fly the initial path stopping to shoot at the views whose "
                                "photos blur in its campaign's flights, fly-through elsewhere (per-view capture "
                                "modes; needs sim.capture.mode fly-through) and its placebos: as many stops at "
                                "views chosen at random (wrp/capture_lever.py)")
    capture_blur_limit_px: float = Field(1.0, gt=0.0, description="capture_stops: stop where the 95th percentile "
                                         "of a view's blur over the campaign's flights exceeds this, px (1 px: "
                                         "the image-side motion during the exposure should not exceed one pixel, "
                                         "Phase One knowledge base KA-01341)")
    slow_legs: bool = Field(False, description="also fly the initial path with the legs arriving at and leaving "
                            "the same blurred views (capture_blur_limit_px) flown at slow_leg_speed_m_s, and its "
                            "placebos: as many legs slowed at random (wrp/capture_lever.py)")
    slow_leg_speed_m_s: float = Field(2.5, gt=0.0, description="slow_legs: the slowed legs' cruise speed, m/s (half "
                                      "the planner's 5 m/s: half the translation blur)")
    out_dir: str | None = Field(None, description="none: logs/<run.name>/evaluate")

    @field_validator("kinds")
    @classmethod
    def _distinct_kinds(cls, kinds: list[str]) -> list[str]:
        if len(set(kinds)) != len(kinds):
            raise ValueError(f"each WRP kind at most once, got {kinds}")
        return kinds


class RobustSection(StrictModel):
    """``wrp.kind: robust`` (issue 30): levers beyond moving a viewpoint, each screened with the oracle on the
    initial path's campaign flights against its own placebos (wrp_eval/wrp/levers.py, README)."""

    levers: list[Literal["redundant", "standoff", "face_standoff"]] = Field(
        ["redundant", "standoff"], min_length=1, description="redundant / standoff: at the riskiest viewpoints; "
        "face_standoff: one lever per face of the proxy, its every surface viewpoint moved back (opt-in: a face "
        "lever and its placebos cost (1 + placebos) x screen_flights oracle calls each)")
    views_fraction: float = Field(0.05, gt=0, le=0.5, description="each lever acts on this share of the "
                                  "viewpoints (the riskiest; at least one): the view budget a redundant lever adds")
    standoff_fraction: float = Field(0.1, gt=0, le=0.5, description="standoff lever: move back by this share "
                                     "of the view's depth (its GSD grows by the same share)")
    risk_flights: int = Field(64, ge=8, le=100_000, description="campaign flights the risk map is measured on")
    screen_flights: int = Field(24, ge=4, le=100_000, description="other campaign flights each lever and its "
                                "placebos are screened on")
    placebos: int = Field(20, ge=1, le=10_000, description="placebo levers (as many viewpoints at random)")
    apply: Literal["recommended", "all"] | list[str] = Field(
        "recommended", description="the levers the robust path applies: those the screening recommends, all of "
        "them whatever their verdict, or the named ones (e.g. [standoff_face_port]) whatever their verdict (to fly "
        "a rejected lever and check the screening); a name no screened lever has is an input error")


class WrpSection(StrictModel):
    """Interval optimisation of a planned path against a trained surrogate (see wrp_eval/wrp/README.md).

    path: the path.json (none: the campaign folder's path.json, the path the surrogate was trained on);
    checkpoint: the surrogate (none: <surrogate.out_dir or logs/<run.name>/surrogate>/surrogate.pt);
    campaign_dir: where r_s is measured (none: surrogate.campaign_dir or logs/<run.name>/campaign).
    threshold_m: t in metres of reconstruction error (none: ``threshold_fraction`` x E_original; the paper's
    0.2-0.3 on E_original 3.185 is 6-9 %). e_original_m: the wind-free path's error (none: from the oracle).
    """

    kind: Literal["iswrp", "swrp", "robust"] = "iswrp"
    path: str | None = None
    checkpoint: str | None = None
    campaign_dir: str | None = None
    threshold_m: float | None = Field(None, ge=0)
    threshold_fraction: float = Field(0.08, ge=0, le=10)
    e_original_m: float | None = Field(None, gt=0)
    e_original_source: Literal["oracle", "surrogate"] = Field("oracle", description="when e_original_m is none: "
                                                             "the oracle on the wind-free path (the paper), or "
                                                             "the surrogate at zero offsets (the surrogate's own "
                                                             "scale, free of any oracle-vs-flight bias)")
    iterations: int = Field(1000, ge=1, le=1_000_000, description="K of Alg. 3: iterations per viewpoint")
    attitude_samples: int = Field(50, ge=1, le=10_000, description="yaw samples of Alg. 4 (the paper's 50)")
    yaw_range_deg: float = Field(20.0, gt=0, le=180, description="Alg. 4 samples yaw offsets in +-this")
    neighbourhood_samples: int = Field(16, ge=2, le=10_000, description="M of Alg. 3 (the paper gives none)")
    step_m: float | None = Field(None, gt=0, description="position moves in +-step per axis (none: the "
                                 "surrogate's training range, so that candidates stay where it has data)")
    step_fallback_m: float = Field(2.0, gt=0)
    neighbourhood: Literal["measured", "ball"] = Field(
        "measured", description="stage 2's samples around a candidate: drawn from the viewpoint's own position-offset "
                                "distribution as the campaign measured it (anisotropic, correlated; issue 18), or "
                                "uniform in the ball of r_s (the paper's 'circle'); measured falls back to the ball "
                                "without a campaign")
    sample_radius: Literal["campaign", "fixed"] = Field("campaign", description="r_s per viewpoint: the "
                                                        "campaign's measured wind-induced offset spread, or fixed")
    sample_radius_m: float = Field(0.5, gt=0, description="r_s when fixed, or when no campaign is available")
    sample_radius_quantile: float = Field(0.95, gt=0, le=1, description="r_s = this quantile of the "
                                          "wind-induced position offset |flown - commanded| per viewpoint")
    swrp_spread: Literal["variance", "std"] = Field("std", description="SWRP accepts when this spread of the "
                                                    "neighbourhood's errors is <= t: the standard deviation (m, "
                                                    "the unit of t; issue 18), or the paper's literal variance "
                                                    "(m^2 against m: the paper-table configs)")
    block_iterations: int = Field(64, ge=1, le=100_000, description="iterations drawn and scored per batch")
    stage2_batch: int = Field(8, ge=1, le=100_000, description="stage-1 survivors whose neighbourhoods are "
                              "scored per batch")
    acceptance: Literal["paper", "improve", "validated"] = Field(
        "validated", description="validated: move a viewpoint only to the best accepted candidate, only "
                                 "when its neighbourhood score beats the unmoved viewpoint's by twice the "
                                 "surrogate's validated single-view error, and only when the oracle confirms it; "
                                 "paper: Alg. 3 as written (the last accepted candidate is kept); improve: as "
                                 "validated with a margin of min_improvement_fraction x t and no oracle (see README)")
    confirm_samples: int = Field(8, ge=2, le=1000, description="acceptance validated: neighbourhood draws per "
                                 "moved viewpoint the oracle scores, with and without the move")
    risk_measure: Literal["mean", "cvar"] = Field("mean", description="ISWRP's neighbourhood score under "
                                                  "improve / validated: the mean error, or its CVaR (the mean of "
                                                  "the worst 1 - cvar_alpha share)")
    cvar_alpha: float = Field(0.8, ge=0, lt=1)
    min_improvement_fraction: float = Field(0.1, ge=0, le=10, description="acceptance improve: the least gain "
                                            "of the neighbourhood score, as a fraction of t")
    improve_candidates: int = Field(16, ge=1, le=100_000, description="acceptance improve: stage-1 survivors "
                                    "(lowest predicted error first) whose neighbourhoods are scored")
    seed: int | None = Field(None, ge=0, description="none: run.seed")
    oracle_error: bool = Field(True, description="score the WRP with the oracle (Table 3's error column)")
    out_dir: str | None = Field(None, description="none: logs/<run.name>/wrp-<kind>")
    threads: int = Field(1, ge=1, le=2)
    evaluate: EvaluateSection = EvaluateSection()
    robust: RobustSection = RobustSection()
