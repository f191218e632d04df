"""``wrp-eval bench --only mission``: how the quickstart mission ends as the wind rises.

For U10 = 0, 4, 8, 12, 15 m/s (turbulence from each trial's mean wind, directions uniform, 64 flights each) the
quickstart experiment's path is flown as planned (``physical`` design) with the default settings, as a campaign
(:func:`wrp_eval.campaign.capture_bench.quickstart_campaign`, the capture bench's flights), and summarised as
the evaluation summarises a path (:func:`wrp_eval.wrp.evaluate.path_summary`): per speed
mission.p_completed.u<U> (the mission flown to its end), mission.p_one_sortie.u<U> (completed on one battery),
mission.mean_sorties.u<U> and mission.mission_time_s.u<U> (of the completed missions: battery swaps and resumes,
sim/mission.py; the time includes the swaps; NaN when none completed), mission.p_meets_spec.u<U>
(error <= 1.1 x the path's wind-free error and completeness >= 0.95: the ``wrp.evaluate`` defaults) and
mission.views_not_taken.u<U> (mean views no sortie took); each note gives the CIs and the ending causes.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from wrp_eval.bench_record import BenchRecord
from wrp_eval.campaign.capture_bench import SPEEDS, quickstart_campaign, quickstart_context
from wrp_eval.campaign.store import TrialStore
from wrp_eval.wrp.config import EvaluateSection
from wrp_eval.wrp.evaluate import path_summary, read_trials
from wrp_eval.wrp.evaluation import PathSummary
from wrp_eval.wrp.jobs import SPEC_ERROR_FACTOR, windfree_error


def _endings(folder: Path) -> dict[str, int]:
    """How the campaign's missions ended: outcome name -> count."""
    names, counts = np.unique([str(e) for e in TrialStore(folder).read_table(["ending"]).column("ending").to_pylist()],
                              return_counts=True)
    return dict(zip(names.tolist(), counts.tolist(), strict=True))


def _ci(row: PathSummary, key: str) -> str:
    ci = getattr(row, key + "_ci")
    return f"[{ci[0]:.3g}, {ci[1]:.3g}]" if ci else "[n/a]"


def speed_records(speed: float, row: PathSummary, endings: dict[str, int]) -> list[BenchRecord]:
    """The mission records of one wind speed from its path summary ``row`` and its ending counts."""
    if (row.spec_error_m is None or row.p_completed is None or row.p_one_sortie is None or row.expected_sorties is None
            or row.mean_mission_time_s is None or row.p_meets_spec is None or row.mean_views_not_taken is None):
        raise ValueError(f"path summary {row.path!r} has no spec or no mission figures (sorties, views not taken)")
    tag = f"u{speed:g}"
    note = (f"quickstart path, physical design, U10 {speed:g} m/s, turbulence from the mean wind, {row.trials} "
            f"flights; endings {endings}; P(meets spec) {_ci(row, 'p_meets_spec')}, sorties "
            f"{_ci(row, 'expected_sorties')}, "
            f"mission time {_ci(row, 'mean_mission_time_s')} s (completed missions), P(completed) "
            f"{_ci(row, 'p_completed')}, P(one sortie) {_ci(row, 'p_one_sortie')} (95 % CIs); "
            f"spec: error <= {row.spec_error_m * 1e3:.2f} mm, completeness >= {row.spec_completeness:g}")
    return [
        BenchRecord(f"mission.p_completed.{tag}", row.p_completed, "probability", note=note),
        BenchRecord(f"mission.p_one_sortie.{tag}", row.p_one_sortie, "probability", note=note),
        BenchRecord(f"mission.mean_sorties.{tag}", row.expected_sorties, "sorties", note=note),
        BenchRecord(f"mission.mission_time_s.{tag}", row.mean_mission_time_s, "s", note=note),
        BenchRecord(f"mission.p_meets_spec.{tag}", row.p_meets_spec, "probability", note=note),
        BenchRecord(f"mission.views_not_taken.{tag}", row.mean_views_not_taken, "views", note=note),
    ]


def run_bench() -> list[BenchRecord]:
    ctx = quickstart_context()
    ev = EvaluateSection()
    spec = (SPEC_ERROR_FACTOR * windfree_error(ctx, ctx.campaign_path), ev.spec_completeness)
    rng = np.random.default_rng(26)
    records = []
    with tempfile.TemporaryDirectory() as tmp:
        for speed in SPEEDS:
            folder = Path(tmp) / f"u{speed:g}"
            quickstart_campaign(ctx, speed, folder)
            row = path_summary(read_trials(f"u{speed:g}", folder), rng, ev.bootstrap, ev.confidence, spec)
            records += speed_records(speed, row, _endings(folder))
    return records
