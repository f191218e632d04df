"""``wrp-eval bench --only robust``: the robust WRP kind's own time on the inspection path (issue 30: wrp.robust_s
<= 10 s at ~143 views on this machine; the oracle's screening is timed apart).

The quickstart ship planned at the inspection gsd (4 mm, ~141 views), ``FLIGHTS`` physical flights at U10 8 m/s
(directions uniform, turbulence from each trial's wind) into a temporary campaign, then ``robust_job`` with the
default ``wrp.robust`` but ``PLACEBOS`` placebos per lever (the screening's cost grows with them; its verdicts
are not this group's business).

wrp.robust_s: the risk map from the campaign's view_registered column and the levers' placement.
wrp.robust_screen_s: the oracle's screening and the capture-error sources, with the number of oracle calls.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from wrp_eval.bench_record import BenchRecord
from wrp_eval.campaign.capture_bench import quickstart_campaign, quickstart_context
from wrp_eval.campaign.view_scaling import INSPECTION_GSD_MM, WIND_M_S, at_gsd
from wrp_eval.wrp.robust import robust_job

FLIGHTS = 96        # the risk map's 64 + the screening's 24, and a few to spare
PLACEBOS = 2


def run_bench() -> list[BenchRecord]:
    ctx = at_gsd(quickstart_context(), INSPECTION_GSD_MM)
    wrp = ctx.config.wrp
    section = wrp.model_copy(update={"robust": wrp.robust.model_copy(update={"placebos": PLACEBOS})})
    with tempfile.TemporaryDirectory() as tmp:
        quickstart_campaign(ctx, WIND_M_S, Path(tmp) / "campaign", flights=FLIGHTS)
        doc = robust_job(ctx, section, Path(tmp) / "robust", Path(tmp) / "campaign")
    n_views = len(doc["p_unregistered"])
    rob = section.robust
    calls = len(rob.levers) * (1 + PLACEBOS) * rob.screen_flights + 6 * rob.screen_flights
    gains = ", ".join(f"{k} {1e3 * v['verdict']['gain_m']:+.3f} mm" for k, v in doc["levers"].items())
    return [
        BenchRecord("wrp.robust_s", doc["robust_s"], "s", "issue 30 target (143 views)", 10.0,
                    f"{n_views} views, {FLIGHTS} flights; {doc['risk_source']}; levers at {len(doc['views'])} views"),
        BenchRecord("wrp.robust_screen_s", doc["screen_s"], "s", None, None,
                    f"{calls} oracle calls at {n_views} views ({len(rob.levers)} levers x (1 + {PLACEBOS} placebos) x "
                    f"{rob.screen_flights} flights + 6 x {rob.screen_flights} for the error sources); robustness "
                    f"gains {gains} (verdicts against {PLACEBOS} placebos are no evidence: timing only)"),
    ]
