"""The tour's direction as a lever (issue 30): the initial tour flown the other way round, and its placebos.

Reversing a tour keeps every viewpoint, leg and transition view; what changes is where the mission starts, from
which side each viewpoint is approached, and *when* each viewpoint is photographed: viewpoint i, shot t_i s after
take-off, is shot about T - t_i s after it (T: the mission time). Under common random numbers every error that
runs with time (the GNSS error, a Gauss-Markov process with a 1,100 s correlation time, Beard & McLain, *Small
Unmanned Aircraft*, 2012, Sec. 7.5, :mod:`wrp_eval.sim.navigation`; the Dryden turbulence; the sea) is then met
at another moment at each viewpoint, so a reversed tour differs from the initial one by a re-draw of those
errors even when its direction does not matter. The oracle keys its own draws by viewpoint
(:attr:`wrp_eval.planning.path.FlightPath.view_id`), so they stay paired.

Placebo (the same machinery as the other WRPs, :mod:`wrp_eval.wrp.evaluate`): the initial tour in its own
direction taking off D s later in the same weather (:meth:`~wrp_eval.planning.path.FlightPath.started_at`),
D uniform in [0, T] (the reversal shifts viewpoint i by |T - 2 t_i|, uniform over [0, T] for a tour at even
pace). A placebo changes only the moment each viewpoint meets those errors; so the reversed tour is recommended
only when its gain beats what re-drawing them gives (the evaluation's rule, unchanged).

The sortie split (where a battery swap breaks a multi-sortie mission) is not a lever here: the simulator swaps
where the battery rule says (sim/mission.py), and a path that one battery flies has nothing to split.
"""

from __future__ import annotations

import numpy as np

from wrp_eval.planning.path import FlightPath


def direction_placebos(initial: FlightPath, count: int, rng: np.random.Generator) -> dict[str, FlightPath]:
    """``count`` placebos of the reversed tour (module docstring): ``initial`` taking off D ~ U(0, T) s later,
    T = ``initial.flight_time_s`` (its cruise time plus one dwell per photo), one draw each."""
    delays = rng.uniform(0.0, initial.flight_time_s, count)
    return {f"placebo-reversed-{k:02d}": initial.started_at(float(delay)) for k, delay in enumerate(delays)}
