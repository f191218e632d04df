"""The ``oracle:`` section of an experiment config: which reconstruction oracle, and its parameters.

Angles in degrees here (the edge of the system); the oracles convert to radians.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from wrp_eval.schema import StrictModel


class SyntheticOracleSection(StrictModel):
    """Parameters of the synthetic multi-view-stereo oracle (see wrp_eval/recon/README.md)."""

    rays_x: int = Field(64, ge=4, le=1024, description="rays per image row (image sampled on a rays_x x rays_y grid)")
    rays_y: int = Field(43, ge=4, le=1024, description="rays per image column")
    max_gsd_m: float = Field(0.05, gt=0, description="a surface point farther than where one pixel covers this "
                             "many metres is not resolved (Smith et al. 2018's d_max, expressed as a GSD)")
    parallax_min_deg: float = Field(5.0, ge=0, lt=90, description="smallest triangulation angle that triangulates")
    parallax_max_deg: float = Field(60.0, gt=0, le=180, description="largest viewing-direction change that still "
                                    "matches: SIFT's limited affine invariance (Lowe 2004; Morel & Yu 2009)")
    incidence_max_deg: float = Field(80.0, gt=0, lt=90, description="largest angle between a ray and the surface "
                                     "normal at which a view can match")
    sigma_px: float = Field(0.5, gt=0, description="matching noise (px) of a feature in a sharp image; blur scales "
                            "it (wrp_eval/recon/image_effects.py)")
    noise_floor_gsd: float = Field(0.5, ge=0, description="model noise of a fused point along the surface normal, as "
                                   "a fraction of the GSD, added in quadrature to the triangulation noise")
    texture_m: float = Field(0.005, gt=0, description="finest scale (m) of the ship surface's texture (paint grain, "
                             "rust, welds): views whose features would be finer (sigma_0 x GSD < texture_m, i.e. "
                             "closer than ~23 m with the default camera) find fewer keypoints")
    keypoints_per_mpx: float = Field(100.0, gt=0, description="matched keypoints per megapixel of a sharp, fully "
                                     "textured image (2400 on the default 24 MP frame): the count behind each "
                                     "view's pose uncertainty")
    prior_position_sigma_m: float | None = Field(
        1.0, gt=0, description="the bundle adjustment's position prior (the recorded GNSS position of each photo, "
                               "CaptureSet.prior_positions), standard deviation in m; null = no priors")
    min_overlap: float = Field(0.1, gt=0, le=1, description="two views are linked (registered together) when "
                               "their overlap (Hepp et al. 2018: shared / mean observed) reaches this")
    min_matched_rays: int = Field(8, ge=1, description="... and they share at least this many matchable rays")
    registration: Literal["components", "incremental"] = Field(
        "incremental", description="components: the largest connected component of the linked views; "
                                  "incremental: an incremental SfM mapper (seed pair, then a view at a time on "
                                  "2D-3D matches to points already triangulated; see README)")
    min_registration_rays: int = Field(
        12, ge=1, description="incremental registration: fewest rays of a view matching triangulated points "
                              "(2D-3D correspondences) to register it (and of triangulating rays of the seed "
                              "pair). 12 = COLMAP's abs_pose_min_num_inliers (15, oracle.colmap) x 0.80, the "
                              "median ratio of this oracle's matchable rays (64 x 43 grid) to COLMAP's verified "
                              "inliers per view pair in the validation sets; scale it with rays_x * rays_y")
    cell_m: float = Field(2.0, gt=0, description="surface-cell size (m) for the co-visibility hashing")
    max_partners: int = Field(12, ge=1, description="candidate partner views per view (most shared cells first)")


class ColmapOracleSection(StrictModel):
    """Parameters of the photogrammetric (pycolmap) validation oracle."""

    image_width_px: int = Field(800, ge=160, le=6000, description="rendered image width (height follows the camera)")
    max_num_features: int = Field(2000, ge=100, description="SIFT features per image")
    match_exhaustive: bool = Field(True, description="exhaustive matching (else sequential)")
    max_camera_residual_m: float | None = Field(
        None, gt=0, description="optional extra failure rule (not in issue 6's definition, off by default): failed "
                                "when the registered cameras are farther than this (RMS, m) from their capture "
                                "positions after georeferencing (a folded model); 5 m separates folded from sound")
    mapper: Literal["global", "incremental"] = Field(
        "incremental", description="COLMAP mapper: incremental with the capture positions as pose priors "
                                   "(default, reproducible) or global SfM (GLOMAP, no priors, not reproducible)")
    prior_position_sigma_m: float | None = Field(
        1.0, gt=0, description="standard deviation (m) of the capture positions given to the incremental mapper "
                               "as position priors (the drone's GPS; ~1 m for a consumer GNSS receiver); "
                               "null = no priors")
    abs_pose_min_num_inliers: int = Field(
        15, ge=6, description="incremental mapper: fewest 2D-3D inliers to register a view (COLMAP's default 30 "
                              "split well-connected 800-px sets into two models; see README)")
    abs_pose_min_inlier_ratio: float = Field(0.1, gt=0, le=1, description="incremental mapper: lowest inlier "
                                             "ratio of a view's registration (COLMAP's default 0.25)")
    num_threads: int = Field(1, ge=-1, description="COLMAP mapping threads (1 = reproducible; -1 = all cores)")


class OracleSection(StrictModel):
    """Which oracle measures a capture set, and how its metrics are computed."""

    kind: Literal["synthetic", "colmap"] = Field("synthetic", description="default oracle")
    tau_m: float = Field(0.10, gt=0, description="distance threshold of completeness / precision / F-score")
    gt_density_per_m2: float = Field(2.0, gt=0, le=100, description="ground-truth surface samples per m^2")
    gt_seed: int = Field(0, ge=0, description="seed of the ground-truth surface sampling (fixed across trials)")
    icp_max_correspondence_m: float = Field(1.0, gt=0, description="ICP correspondence distance")
    icp_max_iterations: int = Field(30, ge=0, description="ICP iterations (0 = no alignment)")
    synthetic: SyntheticOracleSection = SyntheticOracleSection()
    colmap: ColmapOracleSection = ColmapOracleSection()

    @model_validator(mode="after")
    def _parallax_order(self) -> "OracleSection":
        if self.synthetic.parallax_min_deg >= self.synthetic.parallax_max_deg:
            raise ValueError("oracle.synthetic: parallax_min_deg must be below parallax_max_deg")
        return self
