"""The ``planning:`` section of an experiment config (paper Sec. 3 and 5.1; reconstructability terms from
Smith et al. 2018, Min-Max from Zhou et al. 2020; choices where the paper is silent: planning/README.md).

Degrees and millimetres at this edge; the planner converts to radians and metres.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from wrp_eval.camera import Camera
from wrp_eval.schema import StrictModel


class PlanningSection(StrictModel):
    """How the efficient reconstruction path (or a baseline) is planned."""

    method: Literal["ours", "zhou2020", "oblique"] = Field(
        "ours", description="ours (paper Sec. 3), zhou2020 (fixed threshold, no transitions) or oblique")
    # --- camera and distance
    image_width_px: int = Field(6000, ge=16, description="image width (the paper gives no image size)")
    image_height_px: int = Field(4000, ge=16, description="image height")
    gsd_mm: float = Field(7.5, gt=0, description="ground sampling distance at the planned view distance, mm/px "
                          "(7.5 mm/px = 56 m with the default camera; see planning/README.md)")
    distance_m: float | None = Field(None, gt=0, description="planned view distance; overrides gsd_mm")
    max_view_distance_factor: float = Field(
        2.0, gt=1.0, description="d_max of Smith et al. 2018 as a multiple of the planned distance")
    max_incidence_deg: float = Field(85.0, gt=0, le=90, description="a view counts only if theta <= this")
    min_altitude_m: float = Field(5.0, ge=0, description="no viewpoint lower than this above the sea")
    # --- samples and candidates
    sample_overlap: float = Field(0.85, gt=0, lt=1, description="overlap of neighbouring views on the "
                                  "most complex face; sets its Poisson-disk radius (paper Sec. 3.1)")
    max_radius_factor: float = Field(4.0, ge=1, description="cap on a face's radius / the smallest radius "
                                     "(a face of ~zero complexity would otherwise get one sample)")
    tilt_deg: float = Field(25.0, ge=0, lt=80, description="tilt of the extra candidate views about the sample")
    n_tilts: Literal[0, 2, 4] = Field(4, description="tilted candidates per sample (0, 2 about v, 4 about u and v)")
    # --- Min-Max
    threshold: float = Field(0.6, gt=0, description="reconstructability threshold of the most complex face "
                             "(zhou2020: of every face)")
    threshold_scaling: Literal["proportional", "inverse"] = Field(
        "proportional", description="per-face threshold = threshold * (c_i/c_max) [proportional, default] "
        "or * (c_max/c_i) [inverse, the paper's literal wording]; see planning/README.md")
    max_rounds: int = Field(2, ge=0, description="maximisation passes over the view set")
    # --- tour
    tour_solver: Literal["multistart", "ortools", "ga"] = Field(
        "multistart", description="multistart: nearest-neighbour starts from view 0 and 16 random views, "
        "2-opt/Or-opt, iterated local search (deterministic); ortools: OR-Tools guided local search for "
        "tour_time_limit_s; ga: the paper's genetic algorithm")
    tour_time_limit_s: float = Field(0.3, gt=0, description="time limit of the ortools solver, s "
                                     "(its result depends on the machine's load)")
    ga_population: int = Field(120, ge=4)
    ga_generations: int = Field(600, ge=1)
    # --- transitions (paper Def. 3.4-3.5, Alg. 2)
    overlap_min: float = Field(0.4, ge=0, le=1, description="OSMC t_min")
    overlap_max: float = Field(0.8, ge=0, le=1, description="OSMC t_max")
    transitions: bool = Field(True, description="method ours: insert the transition viewpoints (Alg. 2); false "
                              "is the paper's Table 6 comparison (ours without the transition path)")
    # --- flight
    speed_m_s: float = Field(5.0, gt=0, description="cruise speed (paper Sec. 5.1)")
    dwell_s: float = Field(0.5, ge=0, description="hover per photo (Table 7: (159.764 s - 684.566 m / 5 m/s) "
                           "/ 49 views = 0.47 s)")
    endurance_s: float = Field(1500.0, gt=0, description="battery endurance per sortie (25 min)")
    # --- oblique photography baseline (paper Table 8, first row by default)
    oblique_pitch_deg: float = Field(60.0, gt=0, lt=90, description="depression of the 4 oblique cameras")
    front_overlap: float = Field(0.7, ge=0, lt=1)
    side_overlap: float = Field(0.75, ge=0, lt=1)

    @model_validator(mode="after")
    def _check(self) -> "PlanningSection":
        if self.overlap_min > self.overlap_max:
            raise ValueError(f"overlap_min {self.overlap_min} > overlap_max {self.overlap_max}")
        return self

    def camera(self) -> Camera:
        return Camera(image_width_px=self.image_width_px, image_height_px=self.image_height_px)

    def planned_distance_m(self) -> float:
        """The view distance: ``distance_m`` if given, else the one giving ``gsd_mm`` with :meth:`camera`."""
        if self.distance_m is not None:
            return float(self.distance_m)
        return float(self.camera().distance_for_gsd(self.gsd_mm / 1000.0))
