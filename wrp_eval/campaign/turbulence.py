"""Is a campaign's turbulence the one its wind implies? The stress-test note.

MIL-F-8785C ties the low-altitude Dryden intensity to the mean wind at 20 ft (sigma_w = 0.1 W20): a severity
preset (light / moderate / severe: W20 = 15 / 30 / 45 kt) is a fixed W20 whatever the wind, so at U10 = 3-8 m/s
``moderate`` (15.4 m/s) is 2-5 times the turbulence that wind implies. ``from_mean`` (the default) takes W20 from
each trial's own mean wind. A preset stays available as an explicit stress test; when its W20 exceeds
:data:`STRESS_RATIO` times what the trial's mean wind implies, the run says so (:func:`turbulence_stress_note`).
"""

from __future__ import annotations

import numpy as np

from wrp_eval.campaign.config import CampaignSection
from wrp_eval.campaign.sampling import draw_wind, trial_wind_section
from wrp_eval.wind.config import WindSection
from wrp_eval.wind.dryden import severity_w20_mps
from wrp_eval.wind.field import TWENTY_FT_M, build_mean_wind

# a preset is reported when its W20 is more than this many times the W20 of the trial's mean wind
STRESS_RATIO = 1.5
PRESETS = ("light", "moderate", "severe")
# trials whose mean field is built at once (each its own grid, ~1.5 MB for the synthetic default)
CHUNK_TRIALS = 256


def preset_w20_mps(severity: str, sigma_w_m_s: float | None) -> float | None:
    """The W20 (m/s) a trial's turbulence fixes regardless of its wind: 10 sigma_w when given, the preset's,
    or None (``from_mean`` / ``none``: no fixed W20)."""
    if sigma_w_m_s is not None:
        return 10.0 * float(sigma_w_m_s)
    return severity_w20_mps(severity) if severity in PRESETS else None


def turbulence_ratios(base: WindSection, campaign: CampaignSection, root_seed: int, n_trials: int, ship,
                      base_dir=None) -> np.ndarray:
    """(n_trials,) fixed W20 / the W20 of the trial's own mean wind (20 ft over the ship), NaN where the trial's
    turbulence follows its wind (``from_mean``, ``none``). ``ship``: what :func:`build_mean_wind` takes."""
    draws = [draw_wind(campaign, root_seed, k) for k in range(n_trials)]
    fixed = np.array([np.nan if (w := preset_w20_mps(d.severity, d.sigma_w_m_s)) is None else w for d in draws])
    ratios = np.full(n_trials, np.nan)
    rows = np.flatnonzero(np.isfinite(fixed))
    for chunk in np.array_split(rows, max(1, -(-rows.size // CHUNK_TRIALS))) if rows.size else []:
        sections = [trial_wind_section(base, draws[k]) for k in chunk]   # one mean grid each: bounded memory
        at_20ft = np.tile([0.0, 0.0, TWENTY_FT_M], (chunk.size, 1))
        mean = build_mean_wind(sections, ship, base_dir).velocity(at_20ft, 0.0)
        with np.errstate(divide="ignore"):
            ratios[chunk] = fixed[chunk] / np.hypot(mean[:, 0], mean[:, 1])
    return ratios


def turbulence_stress_note(ratios: np.ndarray) -> str | None:
    """One line when some trials' fixed turbulence exceeds :data:`STRESS_RATIO` x what their wind implies, else
    None."""
    finite = ratios[np.isfinite(ratios) & (ratios > STRESS_RATIO)]
    calm = int(np.isinf(ratios).sum())   # a preset over a calm mean wind: infinitely more than it implies
    if not finite.size and not calm:
        return None
    spread = f"median {np.median(finite):.1f}x, max {finite.max():.1f}x" if finite.size else ""
    spread += ("; " if spread else "") + (f"{calm} over a calm mean wind" if calm else "")
    return (f"turbulence stress test: in {finite.size + calm} of {ratios.size} trials the turbulence preset's W20 "
            f"is more than {STRESS_RATIO:g}x what the trial's mean wind implies ({spread}); MIL-F-8785C ties "
            "sigma_w = 0.1 W20 to "
            "the actual wind at 20 ft: `severity: from_mean` flies the turbulence of the wind")
