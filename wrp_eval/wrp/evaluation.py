"""The typed document of ``wrp-eval evaluate`` (evaluate.json): frozen dataclasses with ``to_json_dict`` /
``from_json_dict``, as :class:`wrp_eval.recon.oracle.ReconResult` has.

Units are in the names (m, s); confidence intervals are ``[low, high]`` lists or None (too few samples).
``to_json_dict`` writes the keys in the order the evaluation has always written them, and leaves out the
groups a path's campaign cannot give (no spec, no views-not-taken column, no sorties column): a reader tells
"not measured" (key absent) from "no interval" (null).
"""

from __future__ import annotations

from dataclasses import MISSING, asdict, dataclass, fields
from typing import Any

from wrp_eval.wrp.optimize import Table3Row

Interval = list[float] | None


def _interval(value) -> Interval:
    return None if value is None else [float(value[0]), float(value[1])]


@dataclass(frozen=True)
class PathSummary:
    """One path's flights (evaluate.json ``paths``): the error over the trials that did not fail (mean, std, 95th
    percentile) and the failure rate, each with its CI; with a spec, P(meets spec) (exact CI); where the store
    records them, the views not taken, and the sorties: P(completed), P(one sortie), expected sorties and mean
    mission time of the completed missions (``p_completed`` None: a store from before the battery swaps, whose
    ``expected_sorties`` is n_views / the mean views a flight took)."""

    path: str
    trials: int
    succeeded: int
    failure_rate: float
    failure_rate_ci: Interval
    mean_error_m: float
    mean_error_m_ci: Interval
    std_error_m: float
    std_error_m_ci: Interval
    p95_error_m: float
    p95_error_m_ci: Interval
    spec_error_m: float | None = None
    spec_completeness: float | None = None
    p_meets_spec: float | None = None
    p_meets_spec_ci: Interval = None
    mean_views_not_taken: float | None = None
    mean_views_not_taken_ci: Interval = None
    p_completed: float | None = None
    p_completed_ci: Interval = None
    p_one_sortie: float | None = None
    p_one_sortie_ci: Interval = None
    expected_sorties: float | None = None
    expected_sorties_ci: Interval = None
    mean_mission_time_s: float | None = None
    mean_mission_time_s_ci: Interval = None

    def _groups(self) -> list[tuple[str, ...]]:
        """The key groups this row has, in the document's order."""
        groups: list[tuple[str, ...]] = [
            ("path", "trials", "succeeded", "failure_rate", "failure_rate_ci", "mean_error_m", "mean_error_m_ci",
             "std_error_m", "std_error_m_ci", "p95_error_m", "p95_error_m_ci")]
        if self.spec_error_m is not None:
            groups.append(("spec_error_m", "spec_completeness", "p_meets_spec", "p_meets_spec_ci"))
        if self.mean_views_not_taken is not None:
            groups.append(("mean_views_not_taken", "mean_views_not_taken_ci"))
        if self.p_completed is not None:
            groups.append(("p_completed", "p_completed_ci", "p_one_sortie", "p_one_sortie_ci", "expected_sorties",
                           "expected_sorties_ci", "mean_mission_time_s", "mean_mission_time_s_ci"))
        elif self.expected_sorties is not None:
            groups.append(("expected_sorties", "expected_sorties_ci"))
        return groups

    def to_json_dict(self) -> dict:
        return {key: getattr(self, key) for group in self._groups() for key in group}

    @classmethod
    def from_json_dict(cls, doc: dict) -> "PathSummary":
        known = {f.name for f in fields(cls)}
        kwargs: dict[str, Any] = {k: (_interval(v) if k.endswith("_ci") else v) for k, v in doc.items() if k in known}
        return cls(**kwargs)


@dataclass(frozen=True)
class PairedDifference:
    """``path`` - ``versus`` on the same trial ids (evaluate.json ``paired``): mean error difference over the
    trials where both succeeded (m) and failure-rate difference over all, with paired bootstrap CIs; wins and
    losses count the pairs where ``path`` had the smaller / larger error; p95 error difference (m, the same
    pairs) and, with a spec, the P(meets spec) difference (all pairs), each with its paired bootstrap CI (None
    in documents written before them)."""

    path: str
    versus: str
    paired_trials: int
    both_succeeded: int
    mean_error_diff_m: float
    mean_error_diff_ci: Interval
    wins: int
    losses: int
    failure_rate_diff: float
    failure_rate_diff_ci: Interval
    p95_error_diff_m: float | None = None
    p95_error_diff_ci: Interval = None
    p_meets_spec_diff: float | None = None
    p_meets_spec_diff_ci: Interval = None

    def to_json_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_json_dict(cls, doc: dict) -> "PairedDifference":
        # the fields with a default came later: older documents lack them
        kwargs: dict[str, Any] = {f.name: doc[f.name] if f.default is MISSING else doc.get(f.name, f.default)
                                  for f in fields(cls)}
        return cls(**kwargs)


@dataclass(frozen=True)
class RobustnessVerdict:
    """A WRP against its placebos (evaluate.json ``robustness``): mean robustness gain (m) with its CI over the
    paired trials, the placebos flown and their mean gains (those with a paired success), their 95th
    percentile, and whether the WRP is recommended, with why; ``windfree_error_m``: the WRP's wind-free error
    (None when the verdict was made without it)."""

    gain_m: float
    gain_ci_m: Interval
    paired_trials: int
    placebos_flown: int
    placebo_gains_m: tuple[float, ...]
    placebo_gain_p95_m: float
    recommended: bool
    reason: str
    windfree_error_m: float | None = None

    def to_json_dict(self) -> dict:
        doc = asdict(self)
        doc["placebo_gains_m"] = list(self.placebo_gains_m)
        if self.windfree_error_m is None:
            del doc["windfree_error_m"]
        return doc

    @classmethod
    def from_json_dict(cls, doc: dict) -> "RobustnessVerdict":
        kwargs: dict[str, Any] = {**{f.name: doc.get(f.name) for f in fields(cls)},
                                  "placebo_gains_m": tuple(doc["placebo_gains_m"])}
        return cls(**kwargs)


@dataclass(frozen=True)
class PlaceboControl:
    """How the placebo paths were made (evaluate.json ``placebos``): per WRP that moved, ``per_wrp`` paths;
    the WRPs that moved nothing (no placebos flown for them); moves that kept only their yaw (no flyable
    direction); the method in words."""

    per_wrp: int
    not_flown_for: tuple[str, ...]
    moves_without_a_flyable_direction: int
    how: str

    def to_json_dict(self) -> dict:
        return {"per_wrp": self.per_wrp, "not_flown_for": list(self.not_flown_for),
                "moves_without_a_flyable_direction": self.moves_without_a_flyable_direction, "how": self.how}

    @classmethod
    def from_json_dict(cls, doc: dict) -> "PlaceboControl":
        return cls(doc["per_wrp"], tuple(doc["not_flown_for"]), doc["moves_without_a_flyable_direction"], doc["how"])


@dataclass(frozen=True)
class ForecastVerdict:
    """The path to fly in the forecast wind (evaluate.json ``forecast``): its flights' summary, GO when the lower
    CI bound of P(meets spec) reaches ``go_probability``, the wind (m/s at 10 m, deg from), the one-line summary,
    and the run's stress-test notes (report lines; set by ``wrp-eval run`` when a campaign setting is a stress
    test)."""

    row: PathSummary
    go: bool
    go_probability: float
    wind_speed_10m_m_s: float
    wind_direction_deg: float
    summary: str
    stress_notes: tuple[str, ...] = ()

    def to_json_dict(self) -> dict:
        doc = {**self.row.to_json_dict(), "go": self.go, "go_probability": self.go_probability,
               "wind_speed_10m_m_s": self.wind_speed_10m_m_s, "wind_direction_deg": self.wind_direction_deg,
               "summary": self.summary}
        if self.stress_notes:
            doc["stress_notes"] = list(self.stress_notes)
        return doc

    @classmethod
    def from_json_dict(cls, doc: dict) -> "ForecastVerdict":
        """The older key ``wind_speed_10m_mps`` is read as ``wind_speed_10m_m_s``."""
        return cls(PathSummary.from_json_dict(doc), doc["go"], doc["go_probability"],
                   doc["wind_speed_10m_m_s" if "wind_speed_10m_m_s" in doc else "wind_speed_10m_mps"],
                   doc["wind_direction_deg"], doc["summary"], tuple(doc.get("stress_notes", ())))


@dataclass(frozen=True)
class EvaluationResult:
    """evaluate.json: the bootstrap's confidence and resamples; one :class:`PathSummary` per path (the initial
    path first) and the :class:`PairedDifference` of every other path against it; with the placebo control the
    wind-free errors (path name -> m, placebos included), each WRP's :class:`RobustnessVerdict` and the path to
    fly; how the placebos were made, the forecast verdict, each WRP's Table 3 row and the common-random-numbers
    statement (None / absent where the evaluation did not make them)."""

    confidence: float
    bootstrap_resamples: int
    paths: tuple[PathSummary, ...]
    paired: tuple[PairedDifference, ...]
    windfree_error_m: dict[str, float] | None = None
    robustness: dict[str, RobustnessVerdict] | None = None
    recommended_path: str | None = None
    placebos: PlaceboControl | None = None
    forecast: ForecastVerdict | None = None
    wrp: dict[str, Table3Row] | None = None
    common_random_numbers: str | None = None

    def to_json_dict(self) -> dict:
        doc = {"confidence": self.confidence, "bootstrap_resamples": self.bootstrap_resamples,
               "paths": [p.to_json_dict() for p in self.paths], "paired": [p.to_json_dict() for p in self.paired]}
        if self.robustness is not None:
            doc.update(windfree_error_m=dict(self.windfree_error_m or {}),
                       robustness={k: v.to_json_dict() for k, v in self.robustness.items()},
                       recommended_path=self.recommended_path)
        optional = {"placebos": self.placebos, "forecast": self.forecast}
        doc.update({k: v.to_json_dict() for k, v in optional.items() if v is not None})
        if self.wrp is not None:
            doc["wrp"] = {kind: row.to_json_dict() for kind, row in self.wrp.items()}
        if self.common_random_numbers is not None:
            doc["common_random_numbers"] = self.common_random_numbers
        return doc

    @classmethod
    def from_json_dict(cls, doc: dict) -> "EvaluationResult":
        def typed(key, kind):
            return kind.from_json_dict(doc[key]) if doc.get(key) is not None else None
        return cls(doc["confidence"], doc["bootstrap_resamples"],
                   tuple(PathSummary.from_json_dict(p) for p in doc["paths"]),
                   tuple(PairedDifference.from_json_dict(p) for p in doc["paired"]), doc.get("windfree_error_m"),
                   {k: RobustnessVerdict.from_json_dict(v) for k, v in doc["robustness"].items()}
                   if "robustness" in doc else None, doc.get("recommended_path"), typed("placebos", PlaceboControl),
                   typed("forecast", ForecastVerdict),
                   {k: Table3Row.from_json_dict(v) for k, v in doc["wrp"].items()} if "wrp" in doc else None,
                   doc.get("common_random_numbers"))
