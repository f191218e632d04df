"""Per wind direction, the boundary speed: the highest U10 whose cell meets the threshold.

The search assumes that P(meets spec) does not grow with the wind speed in one direction (stronger mean wind,
stronger turbulence from it, less headway). It first bisects the speed GRID (the middle untested grid speed
between the highest meeting and the lowest failing speed known), then bisects the continuous bracket between
two neighbouring grid speeds until it is at most ``resolution_m_s`` wide. The assumption is not tested: the
search only flies speeds between the highest meeting and the lowest failing speed it knows, so it never sees a
failing cell below a meeting one (a forecast cell is not fed to the search).
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class BoundarySearch:
    """The search in one direction. ``speeds_m_s``: the grid (increasing); call :meth:`next_speed` for the
    next cell to fly (None: done) and :meth:`record` with its outcome."""

    speeds_m_s: tuple[float, ...]
    resolution_m_s: float
    outcomes: dict[float, bool] = field(default_factory=dict)

    def record(self, speed_m_s: float, meets: bool) -> None:
        self.outcomes[float(speed_m_s)] = bool(meets)

    @property
    def highest_meeting(self) -> float | None:
        meeting = [s for s, ok in self.outcomes.items() if ok]
        return max(meeting) if meeting else None

    @property
    def lowest_failing(self) -> float | None:
        """The lowest failing speed above the highest meeting one (None: none flown)."""
        low = self.highest_meeting
        failing = [s for s, ok in self.outcomes.items() if not ok and (low is None or s > low)]
        return min(failing) if failing else None

    def next_speed(self) -> float | None:
        low, high = self.highest_meeting, self.lowest_failing
        inside = [s for s in self.speeds_m_s if s not in self.outcomes
                  and (low is None or s > low) and (high is None or s < high)]
        if inside:
            return inside[(len(inside) - 1) // 2]
        if low is None or high is None:          # below the grid's lowest speed, or above its highest
            return None
        if high - low <= self.resolution_m_s * (1 + 1e-9):
            return None
        return round(0.5 * (low + high), 6)

    @property
    def boundary_m_s(self) -> float | None:
        """The highest speed known to meet the threshold (None: not even the lowest grid speed does)."""
        return self.highest_meeting

    @property
    def above_grid(self) -> bool:
        """The highest grid speed meets the threshold: the boundary lies at or above it."""
        return self.highest_meeting is not None and self.highest_meeting >= self.speeds_m_s[-1]
