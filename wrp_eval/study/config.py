"""The optional ``study:`` section of an experiment config: named variants of the base config, measured
side by side (the paper's Tables 1-8, ``experiments/paper/``).

```yaml
study:
  table: 1                          # the paper's table it reproduces (report heading); optional
  title: proxy height error
  columns: [proxy_height_m, images_adopted, flight_time_s, error_m]   # what the table shows (see COLUMNS)
  variants:
    - name: original
      paper: {images_adopted: 51/51, flight_time_s: 170.832, error_m: 2.94981}
    - name: h-8.7%
      overrides: {ship: {proxy_height_error: -0.0869}}   # deep-merged into the base config
      paper: {...}
    - name: SWRP + secondary offsets
      path: swrp                    # plan (default) | iswrp | swrp: the path the row measures
      random_offsets: true          # each repetition offsets every viewpoint at random before scoring
      repetitions: 5
      paper: [{...}, {...}, ...]    # one mapping per repetition, or one for all
  smallest: {campaign: {n_trials: 16}}   # overrides for `wrp-eval run CONFIG --smallest` (the tests)
  smallest_variants: 2              # --smallest keeps only the first k variants
```
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, field_validator, model_validator

from wrp_eval.schema import StrictModel

# column -> (header, kind): kind "int", "num" (3-4 significant digits) or "text". Units in the header.
COLUMNS: dict[str, tuple[str, str]] = {
    "proxy_height_m": ("proxy height (m)", "num"),
    "height_disturbance_m": ("height disturbance (m)", "num"),
    "views": ("images", "int"),
    "adopted": ("adopted", "int"),
    "images_adopted": ("images/adopted", "text"),
    "transition_views": ("transition views", "int"),
    "H": ("H(S,U)", "num"),
    "R": ("R(U)", "num"),
    "min_s": ("Min (s)", "num"),
    "max_s": ("Max (s)", "num"),
    "minmax_s": ("Min+Max (s)", "num"),
    "tsp_s": ("TSP (s)", "num"),
    "plan_s": ("planning (s)", "num"),
    "pitch_deg": ("pitch (deg)", "num"),
    "front_overlap": ("longitudinal overlap", "num"),
    "side_overlap": ("side overlap", "num"),
    "length_m": ("length (m)", "num"),
    "flight_time_s": ("flight time (s)", "num"),
    "threshold_m": ("threshold (m)", "num"),
    "offset_rate_pct": ("offset rate (%)", "num"),
    "position_offset_m": ("position offset (m)", "num"),
    "rotation_offset_deg": ("rotation offset (deg)", "num"),
    "wrp_time_s": ("WRP time (s)", "num"),
    "error_m": ("reconstruction error (m)", "num"),
    "completeness": ("completeness", "num"),
    "fscore": ("F-score", "num"),
}

PaperValue = float | int | str | None


class RandomOffsets(StrictModel):
    """The random viewpoint offsets of ``random_offsets`` variants (paper Tables 4/5): per viewpoint (dx, dy, dz)
    uniform in +-position_half_width_m and dyaw uniform in +-yaw_half_width_deg. None: the campaign's
    perturbation box (the distribution the surrogate was trained on)."""

    position_half_width_m: float | None = Field(None, ge=0, le=100)
    yaw_half_width_deg: float | None = Field(None, ge=0, le=180)


class StudyVariant(StrictModel):
    """One named variant: ``overrides`` deep-merged into the base config; the row(s) it produces."""

    name: str = Field(min_length=1, max_length=80)
    overrides: dict[str, Any] = Field(default_factory=dict, description="nested mapping of config sections")
    path: Literal["plan", "iswrp", "swrp"] = Field("plan", description="the planned path, or its ISWRP / SWRP "
                                                   "(campaign + surrogate + interval optimisation)")
    random_offsets: bool = Field(False, description="offset every viewpoint at random before scoring")
    repetitions: int = Field(1, ge=1, le=100, description="rows of this variant (fresh offsets each)")
    paper: dict[str, PaperValue] | list[dict[str, PaperValue]] = Field(
        default_factory=dict, description="the paper's figures by column (one mapping, or one per repetition)")

    @field_validator("overrides")
    @classmethod
    def _no_study(cls, value: dict) -> dict:
        if "study" in value:
            raise ValueError("a variant cannot override the study section")
        if isinstance(value.get("run"), dict) and "name" in value["run"]:
            raise ValueError("a variant cannot change run.name (all variants write under logs/<run.name>/)")
        return value

    @model_validator(mode="after")
    def _check(self) -> "StudyVariant":
        if self.repetitions > 1 and not self.random_offsets:
            raise ValueError(f"variant {self.name!r}: repetitions > 1 only make sense with random_offsets "
                             "(everything else is deterministic)")
        if isinstance(self.paper, list) and len(self.paper) not in (1, self.repetitions):
            raise ValueError(f"variant {self.name!r}: paper has {len(self.paper)} rows, repetitions "
                             f"{self.repetitions}")
        return self

    def paper_row(self, repetition: int) -> dict[str, PaperValue]:
        if isinstance(self.paper, dict):
            return self.paper
        return self.paper[repetition if len(self.paper) > 1 else 0]


class StudySection(StrictModel):
    """Variants of the base config run by ``wrp-eval run`` instead of the single pipeline (see
    wrp_eval/study/README.md)."""

    table: int | None = Field(None, ge=1, le=99, description="the paper's table number")
    title: str = Field("", max_length=200)
    columns: list[str] = Field(min_length=1, description="columns of the table, from wrp_eval.study.COLUMNS")
    variants: list[StudyVariant] = Field(min_length=1)
    random_offsets: RandomOffsets = RandomOffsets()
    smallest: dict[str, Any] = Field(default_factory=dict, description="base-config overrides of --smallest")
    smallest_variants: int | None = Field(None, ge=1, description="--smallest keeps the first k variants")
    figures: bool = Field(True, description="a ship-and-path figure per variant in the report")

    @field_validator("columns")
    @classmethod
    def _known_columns(cls, value: list[str]) -> list[str]:
        unknown = [c for c in value if c not in COLUMNS]
        if unknown:
            raise ValueError(f"unknown column(s) {unknown}; known: {sorted(COLUMNS)}")
        return value

    @model_validator(mode="after")
    def _check(self) -> "StudySection":
        names = [v.name for v in self.variants]
        if len(set(names)) != len(names):
            raise ValueError(f"variant names must be unique, got {names}")
        if "study" in self.smallest:
            raise ValueError("smallest cannot override the study section")
        for v in self.variants:
            rows = v.paper if isinstance(v.paper, list) else [v.paper]
            extra = sorted({k for row in rows for k in row} - set(self.columns))
            if extra:
                raise ValueError(f"variant {v.name!r}: paper figures for columns not in study.columns: {extra}")
        return self
