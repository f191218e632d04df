"""The ``surrogate:`` section of an experiment config: training data, split, optimiser, architecture, seed."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from wrp_eval.schema import StrictModel


class SurrogateSection(StrictModel):
    """How ``wrp-eval train`` fits the surrogate.

    campaign_dir: the campaign folder whose ``trials/`` Parquet store is the training data (none:
    ``logs/<run.name>/campaign``, the campaign stage's default). Splits are by trial (a trial is never in two
    splits); the test split is held out and only scored at the end. Early stopping watches the validation
    loss and restores the best epoch's weights.
    """

    campaign_dir: str | None = None
    out_dir: str | None = Field(None, description="checkpoint, metrics and plot folder "
                                "(none: logs/<run.name>/surrogate)")
    val_fraction: float = Field(0.15, gt=0, lt=1)
    test_fraction: float = Field(0.15, gt=0, lt=1)
    epochs: int = Field(1500, ge=1, le=100_000)
    patience: int = Field(150, ge=1, description="epochs without a better validation loss before stopping")
    lr: float = Field(1e-3, gt=0, le=1)
    target: Literal["error", "log_error"] = Field("error", description="what the network regresses: the "
                                                  "error (m) or its log (the error is skewed; measured no better "
                                                  "in metres, see README)")
    lr_decay_patience: int = Field(0, ge=0, description="reduce the learning rate after this many epochs without "
                                   "a better validation loss (torch ReduceLROnPlateau; 0: constant rate, the "
                                   "default: 40 measured worse on 6,000 flights, see README)")
    lr_decay_factor: float = Field(0.5, gt=0, lt=1, description="factor of each learning-rate reduction")
    weight_decay: float = Field(0.0, ge=0)
    batch_size: int = Field(128, ge=1, le=65_536)
    channels: int = Field(16, ge=1, le=1024, description="feature channels of every conv layer (16 and kernel 3: "
                          "fast enough for the optimiser's ~10^6 queries; see README)")
    kernel: int = Field(3, ge=1, le=31, description="conv kernel size along the viewpoint sequence (odd)")
    layers: int = Field(2, ge=1, le=8, description="conv layers")
    hidden: int = Field(64, ge=1, le=4096, description="units of the head's hidden layer")
    pose_channels: bool = Field(True, description="add the planned pose of every viewpoint (x, y, z, cos yaw, "
                                "sin yaw, pitch, index) as constant input channels, so that the network knows "
                                "WHICH viewpoint an offset belongs to")
    inputs: Literal["per_view", "offsets", "scarce"] = Field(
        "per_view", description="per_view: the offsets plus each view's flown geometry (standoff, incidence, "
        "pointing), its conditions at the shutter (blur, wind) and its coverage (unique share, co-visible "
        "partners); offsets: the 4 offsets only (the earlier model, the baseline of the comparison); scarce: "
        "per_view plus the scarce coverage each view's flown pose takes away from the plan (the oracle's "
        "observation model on the ship: ~30 us per view and candidate, README)")
    missing_views: Literal["input", "drop"] = Field("drop", description="trials in which the flight did not take "
                                                   "every view: drop (only complete trials) or input (kept, the "
                                                   "view's 'taken' channel 0). Measured on the 6,000-flight bench "
                                                   "campaign: input gives single-view Spearman 0.08 and a single-"
                                                   "view RMSE of 5.9 mm against drop's 0.43 / 0.26 mm (README)")
    validation_moves: int = Field(60, ge=0, le=100_000, description="after training, single-viewpoint moves "
                                  "scored by the surrogate and by the jitter-averaged oracle: the validated "
                                  "single-view error (metrics single_view.rmse_m) the optimiser's acceptance "
                                  "needs (0: none, and acceptance 'validated' then moves nothing)")
    validation_jitters: int = Field(2, ge=1, le=100, description="oracle jitters averaged per validation move")
    registration_weight: float = Field(0.0, ge=0, le=100, description="weight of an auxiliary loss in training: "
                                       "a per-view logit read linearly off the last conv features learns "
                                       "whether the oracle registered that view (the campaign's view_registered, "
                                       "binary cross-entropy); 0: none. At close range the error's spread is which "
                                       "views register (README)")
    predict_failure: bool = Field(False, description="second output: logit of the trial failing")
    use_failed_trials: bool = Field(False, description="train the error output on failed trials whose error is "
                                    "finite too (default: only trials that did not fail)")
    seed: int | None = Field(None, ge=0, description="seed of the split, the initial weights and the batch "
                             "order (none: run.seed)")
    threads: int = Field(1, ge=1, le=2, description="torch CPU threads (1: on this shared 2-core machine two "
                         "threads measured 10-20x SLOWER than one, OpenMP threads spin-waiting for a busy core)")

    def seed_or(self, run_seed: int) -> int:
        """The training seed: ``seed``, else the run's seed."""
        return self.seed if self.seed is not None else run_seed

    @model_validator(mode="after")
    def _checks(self) -> "SurrogateSection":
        if self.kernel % 2 == 0:
            raise ValueError(f"kernel must be odd (a centred 'same' convolution), got {self.kernel}")
        if self.val_fraction + self.test_fraction >= 0.9:
            raise ValueError("val_fraction + test_fraction must leave at least 10 % of the trials for training")
        return self
