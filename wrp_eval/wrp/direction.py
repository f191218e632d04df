"""The tour's direction as a lever (issue 30): the initial tour flown the other way round, and its placebos.

Reversing a tour keeps every viewpoint, leg and transition view; what changes is where the mission starts (the other
end of the tour; the simulator's home stays the plan's first viewpoint, and the flight out to the start is charged
to the battery), from which side each viewpoint is approached, and *when* each viewpoint is photographed: viewpoint
i, shot t_i s after take-off, is shot about T - t_i s after it (T: the mission time). Under common random numbers
every error that runs with time (the GNSS error, a Gauss-Markov process with a 1,100 s correlation time, Beard &
McLain, *Small Unmanned Aircraft*, 2012, Sec. 7.5, :mod:`wrp_eval.sim.navigation`; the Dryden turbulence; the ship's
motion) is then met at another moment at each viewpoint, so a reversed tour's flights differ from the initial one's
by a re-draw of those errors even when its direction does not matter. The oracle keys its own draws by viewpoint
(:attr:`wrp_eval.planning.path.FlightPath.view_id`), so they stay paired.

Placebo (the same machinery as the other WRPs, :mod:`wrp_eval.wrp.evaluate`): the initial tour in its own
direction, flown again in the same weather (the trial's mean wind and oracle seed) with its flights' own errors
drawn again (:meth:`~wrp_eval.planning.path.FlightPath.redrawn`: navigation errors, ship motion, turbulence and
gusts), one independent draw per placebo. Independent draws are the conservative null: a reversed tour meets the
same realisation run backwards (the same GNSS offset over the tour, its drift reversed), so under "direction does
not matter" its flights stay closer to the initial ones than a placebo's, and its mean gain spreads less than the
placebos'. The reversed tour is recommended only when its gain's CI excludes 0 and beats what re-drawing the
errors gives (the evaluation's rule, unchanged).

The sortie split (where a battery swap breaks a multi-sortie mission) is not a lever here: the simulator swaps
where the battery rule says (sim/mission.py), and a path that one battery flies has nothing to split.
"""

from __future__ import annotations

from dataclasses import replace

from wrp_eval.planning.path import FlightPath


def direction_placebos(initial: FlightPath, count: int) -> dict[str, FlightPath]:
    """``count`` placebos of the reversed tour (module docstring): ``initial`` with draws 1 .. count of its
    flights' own errors."""
    return {f"placebo-reversed-{k:02d}": replace(initial.redrawn(k + 1),
                                                 metadata={**initial.metadata, "placebo_of": "reversed"})
            for k in range(count)}
