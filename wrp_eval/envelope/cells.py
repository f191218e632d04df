"""The cells of an envelope: a wind (U10, direction relative to the ship) and the flights flown in it.

A cell is a campaign of its own (a folder under ``<envelope>/cells/``, resumable like any campaign) whose every
trial flies the path in the same mean wind: the speed and direction are fixed, the turbulence follows the mean
wind (``severity: from_mean``), the path is flown as planned (``physical`` design, no targeted trials). The root
seed is the campaign's for every cell, so flight k of every cell draws the same navigation, ship-motion and
turbulence streams (common random numbers, :mod:`wrp_eval.campaign.sampling`): cells differ only by their wind.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pyarrow.compute as pc

from wrp_eval.campaign.config import CampaignSection, TrialConfig
from wrp_eval.campaign.store import TrialStore
from wrp_eval.envelope.sequential import OPEN, counts_as_meeting, decide, planned_looks
from wrp_eval.wrp.evaluate import PathTrials, meets_spec, read_trials

# Names of the relative wind directions at 45 deg steps (wind FROM, clockwise from the bow, as a seaman
# gives the relative bearing); other steps are named by their angle.
DIRECTION_NAMES = {0: "bow", 45: "starboard bow", 90: "starboard beam", 135: "starboard quarter", 180: "stern",
                   225: "port quarter", 270: "port beam", 315: "port bow"}


def relative_directions(count: int) -> np.ndarray:
    """(count,) deg: wind directions FROM, clockwise from the bow, evenly spaced, the first dead ahead."""
    return np.arange(count) * (360.0 / count)


def direction_name(relative_deg: float) -> str:
    key = round(relative_deg % 360.0, 6)
    return DIRECTION_NAMES.get(int(key), f"{key:g} deg") if float(key).is_integer() else f"{key:g} deg"


@dataclass(frozen=True, order=True)
class CellKey:
    """relative_deg: the wind's direction FROM, clockwise from the bow (0 in calm air: every direction's calm
    cell is the same flights); speed_m_s: U10."""

    relative_deg: float
    speed_m_s: float

    @classmethod
    def of(cls, relative_deg: float, speed_m_s: float) -> "CellKey":
        speed = round(float(speed_m_s), 6)
        return cls(0.0 if speed == 0 else round(float(relative_deg) % 360.0, 6), speed)

    @property
    def folder_name(self) -> str:
        """Unique per key (the key's own rounded floats, not a shorter format)."""
        return "calm" if self.speed_m_s == 0 else f"r{self.relative_deg!r}_u{self.speed_m_s!r}"

    @property
    def direction(self) -> str:
        return "calm" if self.speed_m_s == 0 else direction_name(self.relative_deg)

    def compass_from_deg(self, heading_deg: float) -> float:
        """The meteorological direction (FROM, clockwise from north) of this cell's wind."""
        return (heading_deg + self.relative_deg) % 360.0


def cell_trial(base: TrialConfig, key: CellKey, heading_deg: float, max_flights: int) -> TrialConfig:
    """The trial config of a cell: ``base`` (the experiment's) with every trial in the cell's wind. A
    mesoscale ``wind:`` source is replaced by the synthetic marine profile of the cell's U10: an envelope asks
    what each wind does, whatever the forecast says."""
    doc = base.campaign.model_dump(mode="json")
    doc.update(n_trials=max_flights)
    doc["wind"] = {**doc["wind"], "speed_10m_m_s": key.speed_m_s, "direction_deg": key.compass_from_deg(heading_deg),
                   "turbulence": {"severity": "from_mean", "sigma_w_m_s": None},
                   "mesoscale": {"file": None, "time": None}}
    doc["perturbation"] = {**doc["perturbation"], "design": "physical", "targeted_share": 0.0}
    doc["outputs"] = {**doc["outputs"], "rerun": False}
    wind = base.wind if base.wind.source == "synthetic" else base.wind.model_copy(
        update={"source": "synthetic", "file": None, "time": None})
    return base.model_copy(update={"campaign": CampaignSection.model_validate(doc), "wind": wind})


@dataclass
class Cell:
    """One cell's state. ``flights``: the flights its test has counted (whole looks, trial ids 0..flights-1);
    ``meets``: (flights,) bool, each flight met the spec; ``decision``: the sequential test's
    (:mod:`wrp_eval.envelope.sequential`)."""

    key: CellKey
    folder: Path
    trial: TrialConfig
    flights: int = 0
    meets: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    decision: str = OPEN

    @property
    def finished(self) -> bool:
        return self.decision != OPEN

    @property
    def successes(self) -> int:
        return int(self.meets[:self.flights].sum())

    @property
    def p_hat(self) -> float:
        return self.successes / self.flights if self.flights else float("nan")


@dataclass(frozen=True)
class TestRule:
    """The sequential test's settings: the flights per look, the most flights of a cell, the threshold on
    P(meets spec), the confidence, and the spec (error m, completeness)."""

    look_flights: int
    max_flights: int
    threshold: float
    confidence: float
    spec: tuple[float, float]

    @property
    def looks(self) -> int:
        return planned_looks(self.max_flights, self.look_flights)

    def next_target(self, flights: int) -> int:
        return min(self.max_flights, flights + self.look_flights)

    def meets(self, cell: Cell) -> bool:
        return counts_as_meeting(cell.decision, cell.p_hat, self.threshold)


def stored_trials(cell: Cell) -> PathTrials | None:
    """The cell's stored flights (None: none yet)."""
    if not TrialStore(cell.folder).chunk_files():
        return None
    return read_trials(cell.key.folder_name, cell.folder)


def replay(cell: Cell, rule: TestRule) -> None:
    """Re-run the cell's test over its stored flights, look by look (a resumed envelope decides exactly as the
    run that flew them); stops at the first look not wholly stored."""
    trials = stored_trials(cell)
    if trials is None:
        return
    # a trial id stored twice (two runs on one folder before the envelope lock): its first record counts
    ids, first = np.unique(trials.trial_id, return_index=True)
    met = meets_spec(trials, *rule.spec)[first]
    flights, decision = 0, OPEN
    while decision == OPEN:
        target = rule.next_target(flights)
        if not np.array_equal(ids[:target], np.arange(target)):
            break
        flights = target
        decision = decide(int(met[:flights].sum()), flights, rule.threshold, rule.confidence, rule.looks,
                          last=flights >= rule.max_flights)
    cell.flights, cell.meets, cell.decision = flights, met[:flights], decision


def ending_counts(folder: Path, flights: int) -> dict[str, int]:
    """How the cell's first ``flights`` flights ended (sim/mission.py's names; "error" for a trial that raised,
    "unknown" where the evaluator reports no ending)."""
    table = TrialStore(folder).read_table(["trial_id", "ending", "error"])
    table = table.filter(pc.less(table.column("trial_id"), flights))
    names = pc.if_else(pc.is_valid(table.column("error")), "error",
                       pc.fill_null(table.column("ending"), "unknown"))
    counts = pc.value_counts(names)
    return {str(c["values"]): int(c["counts"]) for c in counts.to_pylist()}


def limiting_cause(trials: PathTrials, endings: dict[str, int], spec: tuple[float, float]) -> str:
    """What kept the flights that missed the spec from meeting it, the most frequent first: the mission's ending
    when it was not completed, else the reconstruction (error above spec, completeness below it, failed)."""
    if trials.completeness is None:
        raise ValueError(f"{trials.name}: no completeness column to tell the reconstruction's causes apart")
    causes: Counter = Counter({name: n for name, n in endings.items() if name not in ("completed", "unknown")})
    done = trials.completed if trials.completed is not None else np.ones(trials.trial_id.size, bool)
    with np.errstate(invalid="ignore"):
        over = done & ~trials.failed & (trials.error_m > spec[0])
        incomplete = done & ~trials.failed & ~over & (trials.completeness < spec[1])
    causes.update({"error above spec": int(over.sum()), "completeness below spec": int(incomplete.sum()),
                   "reconstruction failed": int((done & trials.failed).sum())})
    named = [(n, c) for n, c in causes.most_common() if c > 0]
    return ", ".join(f"{n} ({c})" for n, c in named) if named else "none"
