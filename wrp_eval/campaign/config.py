"""The ``campaign:`` section of an experiment config.

Every scenario input is either a fixed value or a stated distribution::

    speed_10m_m_s: 8.0                                   # fixed
    speed_10m_m_s: {dist: uniform, low: 4, high: 12}     # drawn per trial
    direction_deg: {dist: normal, mean: 270, std: 20, clip: [200, 340]}
    severity: {dist: choice, values: [light, moderate, severe], weights: [0.3, 0.5, 0.2]}
"""

from __future__ import annotations

from typing import Annotated, Literal, TypeVar, Union, get_args

from pydantic import Discriminator, Field, Tag, model_validator

from wrp_eval.recon.config import OracleSection
from wrp_eval.schema import StrictModel, reading_stored, renamed_keys
from wrp_eval.ship.config import ShipSection
from wrp_eval.sim.config import SimSection
from wrp_eval.wind.config import WindSection


class Uniform(StrictModel):
    """Uniform on [low, high)."""

    dist: Literal["uniform"]
    low: float
    high: float

    @model_validator(mode="after")
    def _ordered(self) -> "Uniform":
        if not self.high > self.low:
            raise ValueError(f"uniform needs high > low, got low={self.low}, high={self.high}")
        return self


class Normal(StrictModel):
    """Normal(mean, std), optionally clipped to [clip[0], clip[1]]."""

    dist: Literal["normal"]
    mean: float
    std: float = Field(gt=0)
    clip: tuple[float, float] | None = None

    @model_validator(mode="after")
    def _clip_ordered(self) -> "Normal":
        if self.clip is not None and not self.clip[1] > self.clip[0]:
            raise ValueError(f"normal clip needs [low, high] with high > low, got {list(self.clip)}")
        return self


class Choice(StrictModel):
    """One of ``values`` (equal weights unless ``weights`` are given; they are normalised)."""

    dist: Literal["choice"]
    values: list[float | int | str] = Field(min_length=1)
    weights: list[float] | None = None

    @model_validator(mode="after")
    def _weights_match(self) -> "Choice":
        if self.weights is not None:
            if len(self.weights) != len(self.values):
                raise ValueError(f"choice has {len(self.values)} values but {len(self.weights)} weights")
            if any(w < 0 for w in self.weights) or sum(self.weights) <= 0:
                raise ValueError("choice weights must be >= 0 with a positive sum")
        return self


Distribution = Annotated[Union[Uniform, Normal, Choice], Field(discriminator="dist")]
Severity = Literal["none", "from_mean", "light", "moderate", "severe"]


def _fixed_or_dist(value) -> str:
    """Route a value to one branch (so that an error names that branch only): a mapping is a distribution."""
    return "dist" if isinstance(value, (dict, Uniform, Normal, Choice)) else "fixed"


_Fixed = TypeVar("_Fixed")
_Dist = TypeVar("_Dist")

# FixedOrDist[fixed, dist]: the type "a fixed ``fixed`` value, or a ``dist`` distribution ({dist: ...})"
FixedOrDist = Annotated[Union[Annotated[_Fixed, Tag("fixed")], Annotated[_Dist, Tag("dist")]],
                        Discriminator(_fixed_or_dist)]
NumberOrDist = FixedOrDist[float, Distribution]
TextOrDist = FixedOrDist[str, Choice]


class TurbulenceSpec(StrictModel):
    """Dryden turbulence of a trial (the wind stage's MIL-F-8785C model): a severity (``from_mean``: W20 from
    the trial's mean wind at 20 ft; light/moderate/severe: the presets; none), or an explicit intensity
    ``sigma_w_m_s`` (then W20 = 10 sigma_w), which wins when given."""

    severity: FixedOrDist[Severity, Choice] = "from_mean"
    sigma_w_m_s: NumberOrDist | None = None

    @model_validator(mode="before")
    @classmethod
    def _old_keys(cls, data):
        return renamed_keys(data, {"sigma_w_mps": "sigma_w_m_s"}, "campaign.wind.turbulence")

    @model_validator(mode="after")
    def _known_severities(self) -> "TurbulenceSpec":
        if isinstance(self.severity, Choice):
            bad = [v for v in self.severity.values if v not in get_args(Severity)]
            if bad:
                raise ValueError(f"turbulence severity choice has unknown value(s) {bad}")
        return self


class MesoscaleSpec(StrictModel):
    """Which mesoscale output a trial flies in, for ``wind.source`` wrf / mm5: the netCDF ``file`` and the
    ISO ``time`` in it (each fixed, a choice, or none = the ``wind:`` section's). Ignored by the synthetic
    source, whose mean field comes from the drawn speed and direction."""

    file: TextOrDist | None = None
    time: TextOrDist | None = None


class WindScenario(StrictModel):
    """The distribution of the wind each trial flies in. Conventions are the ``wind:`` section's: speed at
    10 m above the sea (m/s), ``direction_deg`` meteorological (the bearing the wind blows FROM, clockwise
    from north). The rest of the wind model (grid, interpolation, gusts, Charnock) comes from ``wind:``."""

    speed_10m_m_s: NumberOrDist = Field(default_factory=lambda: Uniform(dist="uniform", low=3.0, high=9.0))
    direction_deg: NumberOrDist = Field(default_factory=lambda: Uniform(dist="uniform", low=0.0, high=360.0))
    turbulence: TurbulenceSpec = TurbulenceSpec()
    mesoscale: MesoscaleSpec = MesoscaleSpec()


class Perturbation(StrictModel):
    """How each trial's commanded viewpoints differ from the plan, and the paper's extra disturbance.

    design ``physical`` (the default): the viewpoints are flown as planned (commanded offsets 0) and the flown
    offsets are exactly the flight's (no extra disturbance, whatever ``flown_disturbance`` says): everything in
    a capture comes from the flight (navigation, gimbal, wind, capture mode, ship motion); except that in a
    ``targeted_share`` of the trials a run of 1..``targeted_max_views`` consecutive viewpoints is commanded off
    the plan (Gaussian, ``targeted_position_sigma_m`` / ``targeted_yaw_sigma_deg``), so that single viewpoints
    and short segments move on their own in the data, as the optimiser's queries do.
    ``none``: commanded offsets 0, with the paper's extra disturbance of the flown offsets.

    design ``box``: per viewpoint (dx, dy, dz, dyaw) uniform in [-half_width, +half_width], drawn as a
    scrambled Sobol sequence (``sampler: sobol``, extendable: trial k is point k whatever the trial count) or a
    Latin hypercube over the campaign's n_trials (``sampler: lhs``; the design then depends on n_trials).

    design ``common``: the paper's own data (Sec. 4.1): the offsets of a trial are the response of the UAV to ONE
    wind situation, so they are shared by the viewpoints, each disturbed by 20 %. A common offset c (4 values)
    is drawn in the box (Sobol / LHS over 4 dimensions, as above), and viewpoint k gets
    c * (1 + e_k) + view_jitter * half_width * u_k with e_k ~ U(-view_disturbance, +view_disturbance) and
    u_k ~ U(-1, 1) per component. The additive jitter lets the surrogate see single viewpoints move on their
    own, which is what the interval optimiser asks it about. ``solo_views`` k > 0: k viewpoints of each trial
    (uniform, without replacement) take instead an offset of their own, uniform in the box: the optimiser's
    query (one viewpoint moved against the others) appears in the data.
    ``flown_disturbance``: the paper's Sec. 4.1 "additional 20 % random disturbance": the wind-induced part of
    every flown offset is scaled by (1 + e), e ~ U(-f, f), f = flown_disturbance (0 disables it).
    """

    design: Literal["physical", "none", "box", "common"] = "physical"
    sampler: Literal["sobol", "lhs"] = "sobol"
    position_half_width_m: float = Field(2.0, ge=0)
    yaw_half_width_deg: float = Field(20.0, ge=0, le=180)
    view_disturbance: float = Field(0.2, ge=0, le=1, description="design common: relative per-viewpoint "
                                    "disturbance of the common offset (the paper's 20 %)")
    view_jitter: float = Field(0.05, ge=0, le=1, description="design common: additive per-viewpoint jitter, as "
                               "a fraction of the half widths")
    solo_views: int = Field(0, ge=0, description="design common: viewpoints per trial with an independent "
                            "offset uniform in the box instead of the common one")
    flown_disturbance: float = Field(0.2, ge=0, le=1)
    targeted_share: float = Field(0.2, ge=0, le=1, description="design physical: the share of trials in which a "
                                  "short run of consecutive viewpoints is commanded off the plan (issue 18: the "
                                  "optimiser's one-viewpoint queries must lie inside the training data)")
    targeted_max_views: int = Field(5, ge=1, description="design physical: the longest run of targeted viewpoints "
                                    "(its length uniform in 1..this)")
    targeted_position_sigma_m: float = Field(1.5, ge=0, description="design physical: std per axis (m) of a "
                                             "targeted viewpoint's commanded offset: twice the consumer GNSS "
                                             "error the flights carry (1.5 m 95 % -> 0.77 m std)")
    targeted_yaw_sigma_deg: float = Field(8.0, ge=0, le=90, description="design physical: std (deg) of a "
                                          "targeted viewpoint's commanded yaw offset (the flights' own: ~1.6 deg "
                                          "median; the optimiser moves yaw within +-20 deg)")


class Backend(StrictModel):
    """Where trials run. ``local``: a process pool (workers: processes, default the CPU count; 0 runs in the
    calling process). ``ray``: Ray tasks (address: a cluster, e.g. ``ray://head:10001`` or ``auto``; none
    starts a local Ray instance with ``workers`` CPUs). ``max_attempts``: tries of a trial that raises
    before it is recorded failed with its error."""

    kind: Literal["local", "ray"] = "local"
    workers: int | None = Field(None, ge=0)
    address: str | None = None
    max_attempts: int = Field(2, ge=1, le=10)


class Outputs(StrictModel):
    """dir: campaign folder (default logs/<run.name>/campaign); chunk_trials: records per Parquet chunk
    (a kill loses at most the chunk in flight); flush_s: a partial chunk is written after this long;
    rerun: write <dir>/campaign.rrd; trajectory_points: down-sampled trajectory length stored per trial."""

    dir: str | None = None
    chunk_trials: int = Field(32, ge=1)
    flush_s: float = Field(20.0, gt=0)
    rerun: bool = True
    trajectory_points: int = Field(200, ge=2, le=100_000)


class CampaignSection(StrictModel):
    """A Monte Carlo campaign: n_trials flights of one path, each under a sampled wind and perturbation.

    path: a path.json file; none plans one from the ``planning:`` section. seed: root of every trial's
    random draws (none: ``run.seed``). batch_size: flights advanced together by one worker task (large
    batches amortise the simulator's per-step numpy work: measured on the 2-core machine, ~8 s per 48-view
    flight at batch 8, 0.73 s at 64; a kill loses at most the batches in flight).
    oracle: which reconstruction oracle scores the capture poses.
    """

    path: str | None = None
    n_trials: int = Field(100, ge=1, le=10_000_000)
    seed: int | None = Field(None, ge=0)
    batch_size: int = Field(64, ge=1, le=4096)
    wind: WindScenario = WindScenario()
    perturbation: Perturbation = Perturbation()
    oracle: Literal["synthetic", "colmap"] = "synthetic"
    backend: Backend = Backend()
    outputs: Outputs = Outputs()


class TrialConfig(StrictModel):
    """What one trial (a flight and its scoring) reads of an experiment: the ``ship:``, ``wind:``, ``sim:``,
    ``oracle:`` and ``campaign:`` sections. It is the campaign's fingerprint and what a worker receives (a
    validated model, pickled to processes and Ray nodes, never validated again there); the path enters
    through its digest, the root seed beside it."""

    ship: ShipSection = ShipSection()
    wind: WindSection = WindSection()
    sim: SimSection = SimSection()
    oracle: OracleSection = OracleSection()
    campaign: CampaignSection = CampaignSection()

    @classmethod
    def from_stored(cls, doc: dict) -> "TrialConfig":
        """The trial config of a stored campaign.json ``config`` (older campaigns stored the whole experiment
        document: only the trial sections are read)."""
        with reading_stored():
            return cls.model_validate({name: doc[name] for name in cls.model_fields if name in doc})
