"""Interval optimisation of a path against the surrogate: the paper's Alg. 3 (ISWRP) and its SWRP variant,
with Alg. 4 for the attitude.

Per viewpoint i, in path order, with the viewpoints before i at their accepted offsets and those after at 0:

* iteration j (j < K) draws a position offset c_j uniform in [-step, step]^3 and finds its best yaw offset
  a_j among ``attitude_samples`` draws in [-Y, Y] (Alg. 4: argmin of the surrogate); E_j = f(c_j, a_j).
* stage 1 (Alg. 3 line 9): |E_j - E_original| <= t.
* stage 2 (lines 10-15): M points P_k uniform in the ball of radius r_s_i around c_j (the paper's "sampling
  circle", in 3-D), each with its Alg. 4 yaw; ISWRP accepts when |mean_k E_k - E_original| <= t (Def. 4.2),
  SWRP when the variance of the E_k is <= t (Def. 4.3; ``swrp_spread: std`` uses the standard deviation).
* an accepted iteration overwrites the kept offset (lines 16-17), so the result is the LAST accepted one.

Reading of the paper's pseudo-code (documented choices, see README.md):
* line 16 keeps ``P_i`` (= the old offset, which would never change anything): we keep the candidate P'_i;
* line 13 accumulates ``R_mean`` but line 15 tests ``E_mean``: we test the mean of the M sample errors;
* line 6 draws around ``p_offset``; we draw every candidate around the PLANNED position, independently:
  "last accepted wins" then means that every iteration is independent of the others, so the K iterations
  are scored in batches, latest first, and the scan stops at the first (latest) accepted one -- the same
  answer as the sequential loop, at a fraction of the queries. (A random walk from the last accepted offset
  samples the same acceptable set; ours keeps every candidate inside the +-step box.)
* SWRP keeps stage 1 (Alg. 3 is written for ISWRP; the SWRP of Sec. 4.2 changes only the neighbourhood test).

Every random number of viewpoint i comes from ``SeedSequence(seed, spawn_key=(i, block))`` drawn per block of
``block_iterations`` iterations, so results do not depend on how the batches are evaluated.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, fields, replace
from functools import cached_property

import numpy as np

from wrp_eval.ship.nofly import flyable
from wrp_eval.surrogate.model import Surrogate, ViewQuery
from wrp_eval.wrp.config import WrpSection


@dataclass(frozen=True)
class WrpParams:
    """The optimiser's parameters: the ``wrp:`` section's settings (:meth:`of`, the one place they are read) with
    what the inputs measured. kind: 'iswrp' | 'swrp'; threshold_m: t (m of error); e_original_m: E_original
    (m); sample_radius_m: r_s per viewpoint (n_views,) m (the ball neighbourhood); iterations: K;
    attitude_samples: Alg. 4's sample count; yaw_range_rad: Y; neighbourhood_samples: M; step_m: position move
    bound per axis (m); swrp_spread: 'std' | 'variance'; block_iterations: iterations per draw/score batch;
    stage2_batch: stage-1 survivors scored per batch.

    acceptance "paper": Alg. 3 as written (the last accepted candidate is kept); "improve": a viewpoint moves only
    to the accepted candidate with the best neighbourhood score, and only when that beats the unmoved viewpoint's
    own neighbourhood by min_improvement_fraction * t (with a surrogate that is flat for one-viewpoint moves,
    Alg. 3 moves every viewpoint at random: README), looking at improve_candidates survivors; "validated": as
    "improve", but the least gain is twice the surrogate's validated single-view error ``validated_error_m`` (m;
    None: an unvalidated surrogate, nothing moves), and the oracle then confirms each move
    (:mod:`wrp_eval.wrp.confirm`). risk_measure: ISWRP's neighbourhood summary, the mean or the CVaR (the mean
    of the worst 1 - cvar_alpha share). Flight safety of the moved viewpoints (the planner's, Sec. 3.1):
    base_positions (n, 3) m planned, min_altitude_m above the sea, no_fly_bounds (2, 3); None: unconstrained.
    neighbour_cholesky (n, 3, 3) m: the measured neighbourhood, per viewpoint the Cholesky factor of the
    campaign's position-offset covariance (neighbours drawn from N(candidate, L L^T)); None: the ball of r_s."""

    kind: str
    threshold_m: float
    e_original_m: float
    sample_radius_m: np.ndarray
    iterations: int
    attitude_samples: int
    yaw_range_rad: float
    neighbourhood_samples: int
    step_m: float
    swrp_spread: str
    block_iterations: int
    stage2_batch: int
    acceptance: str
    min_improvement_fraction: float
    improve_candidates: int
    validated_error_m: float | None
    risk_measure: str
    cvar_alpha: float
    base_positions: np.ndarray | None
    min_altitude_m: float
    no_fly_bounds: np.ndarray | None
    neighbour_cholesky: np.ndarray | None

    @classmethod
    def of(cls, section: WrpSection, *, threshold_m: float, e_original_m: float, sample_radius_m: np.ndarray,
           step_m: float, validated_error_m: float | None = None, neighbour_cholesky: np.ndarray | None = None,
           base_positions: np.ndarray | None = None, min_altitude_m: float = 0.0,
           no_fly_bounds: np.ndarray | None = None) -> "WrpParams":
        """The parameters of ``section`` (its settings) with the measured inputs; the keyword defaults mean
        "not measured" (no validated error, the ball neighbourhood, no flight-safety constraint)."""
        return cls(kind=section.kind, threshold_m=threshold_m, e_original_m=e_original_m,
                   sample_radius_m=sample_radius_m, iterations=section.iterations,
                   attitude_samples=section.attitude_samples, yaw_range_rad=float(np.radians(section.yaw_range_deg)),
                   neighbourhood_samples=section.neighbourhood_samples, step_m=step_m,
                   swrp_spread=section.swrp_spread, block_iterations=section.block_iterations,
                   stage2_batch=section.stage2_batch, acceptance=section.acceptance,
                   min_improvement_fraction=section.min_improvement_fraction,
                   improve_candidates=section.improve_candidates, validated_error_m=validated_error_m,
                   risk_measure=section.risk_measure, cvar_alpha=section.cvar_alpha, base_positions=base_positions,
                   min_altitude_m=min_altitude_m, no_fly_bounds=no_fly_bounds,
                   neighbour_cholesky=neighbour_cholesky)

    def feasible(self, view: int, offsets: np.ndarray) -> np.ndarray:
        """(B,) bool: position offsets (B, 3) of ``view`` that keep it flyable (the ship stage's one predicate,
        :func:`wrp_eval.ship.nofly.flyable`: above the minimum altitude and out of the no-fly box)."""
        if self.base_positions is None:
            return np.ones(len(offsets), bool)
        return flyable(np.asarray(self.base_positions)[view] + offsets, self.no_fly_bounds, self.min_altitude_m)

    def __post_init__(self) -> None:
        if self.kind not in ("iswrp", "swrp"):
            raise ValueError(f"kind must be iswrp or swrp, got {self.kind!r}")
        if self.swrp_spread not in ("variance", "std"):
            raise ValueError(f"swrp_spread must be variance or std, got {self.swrp_spread!r}")
        if self.acceptance not in ("paper", "improve", "validated"):
            raise ValueError(f"acceptance must be paper, improve or validated, got {self.acceptance!r}")
        if self.risk_measure not in ("mean", "cvar") or not 0.0 <= self.cvar_alpha < 1.0:
            raise ValueError(f"risk_measure must be mean or cvar with 0 <= cvar_alpha < 1, got "
                             f"{self.risk_measure!r} / {self.cvar_alpha}")

    def improvement_margin_m(self) -> float:
        """The least gain of the neighbourhood score for a move (m; inf: no move can be justified)."""
        if self.acceptance == "validated":
            if self.validated_error_m is None:
                return float("inf")
            margin = 2.0 * self.validated_error_m
            # SWRP on the literal variance scores in m^2: the margin in the same unit
            return margin ** 2 if self.kind == "swrp" and self.swrp_spread == "variance" else margin
        return self.min_improvement_fraction * self.threshold_m


class IterationDraws:
    """The random numbers of one block of iterations of one viewpoint (B = block_iterations, A = attitude
    samples, M = neighbourhood samples): position (B, 3) m; yaw (B, A) rad; neighbour_offset (B, M, 3) m
    (already scaled by r_s); neighbour_yaw (B, M, A) rad.

    neighbour_yaw is the stream's last draw and the largest (B M A numbers), and only the few candidates that
    reach stage 2 read it: it is drawn on first use, the same numbers as drawn at once."""

    def __init__(self, position: np.ndarray, yaw: np.ndarray, neighbour_offset: np.ndarray,
                 rng: np.random.Generator, yaw_range_rad: float, attitudes: int):
        self.position, self.yaw, self.neighbour_offset = position, yaw, neighbour_offset
        self._rng, self._yaw_range_rad, self._attitudes = rng, yaw_range_rad, attitudes

    @cached_property
    def neighbour_yaw(self) -> np.ndarray:
        y = self._yaw_range_rad
        return self._rng.uniform(-y, y, size=self.neighbour_offset.shape[:2] + (self._attitudes,))


def iteration_draws(seed: int, view: int, block: int, params: WrpParams) -> IterationDraws:
    """Draws of iterations [block * B, (block + 1) * B) of viewpoint ``view``."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(view, block)))
    b, a, m = params.block_iterations, params.attitude_samples, params.neighbourhood_samples
    y = params.yaw_range_rad
    position = rng.uniform(-params.step_m, params.step_m, size=(b, 3))
    yaw = rng.uniform(-y, y, size=(b, a))
    direction = rng.normal(size=(b, m, 3))
    if params.neighbour_cholesky is not None:   # where the flight really puts the drone: anisotropic, correlated
        neighbour = direction @ np.asarray(params.neighbour_cholesky[view]).T
    else:
        direction /= np.linalg.norm(direction, axis=-1, keepdims=True)
        neighbour = direction * params.sample_radius_m[view] * rng.uniform(size=(b, m, 1)) ** (1.0 / 3.0)  # ball
    return IterationDraws(position, yaw, neighbour, rng, y, a)


def best_attitude(query: ViewQuery, view: int, positions: np.ndarray,
                  yaws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Alg. 4 for many positions in ONE surrogate pass: positions (..., 3), yaws (..., A) ->
    (best yaw (...), its error (...))."""
    lead = positions.shape[:-1]
    a = yaws.shape[-1]
    cand = np.concatenate([np.repeat(positions.reshape(-1, 1, 3), a, axis=1), yaws.reshape(-1, a, 1)], axis=2)
    err = query.errors(view, cand.reshape(-1, 4)).reshape(-1, a)
    k = np.argmin(err, axis=1)
    rows = np.arange(err.shape[0])
    return yaws.reshape(-1, a)[rows, k].reshape(lead), err[rows, k].reshape(lead)


def neighbourhood_statistic(errors: np.ndarray, params: WrpParams) -> np.ndarray:
    """(..., M) sample errors -> (...) the quantity compared with t: |mean - E_original| (ISWRP) or the
    variance / standard deviation (SWRP; population statistics, ddof 0)."""
    if params.kind == "iswrp":
        return np.abs(errors.mean(axis=-1) - params.e_original_m)
    var = errors.var(axis=-1)
    return var if params.swrp_spread == "variance" else np.sqrt(var)


@dataclass
class WrpResult:
    """offsets (n_views, 4): accepted (dx, dy, dz m, dyaw rad) per viewpoint (zeros where not moved); moved (n,)
    bool; accepted_iteration (n,) int (-1: none); stage1_error (n,) m: E of the accepted candidate;
    neighbourhood_stat (n,): its stage-2 statistic; predicted_error_m: surrogate error of the whole WRP;
    seconds; forward_calls / queries: batched surrogate passes and candidates scored; params."""

    offsets: np.ndarray
    moved: np.ndarray
    accepted_iteration: np.ndarray
    stage1_error: np.ndarray
    neighbourhood_stat: np.ndarray
    predicted_error_m: float
    seconds: float
    forward_calls: int
    queries: int
    params: WrpParams
    iterations_scored: int = 0
    extra: dict = field(default_factory=dict)

    def table3(self) -> "Table3Row":
        """The paper's Table 3 row of this optimisation (without the oracle's error)."""
        position_m, rotation_deg = offset_totals(self.offsets)
        return Table3Row(kind=self.params.kind, threshold_m=float(self.params.threshold_m),
                         offset_rate_pct=100.0 * float(self.moved.mean()), position_offset_m=position_m,
                         rotation_offset_deg=rotation_deg, time_s=float(self.seconds),
                         viewpoints=int(self.moved.size), moved=int(self.moved.sum()),
                         surrogate_error_m=float(self.predicted_error_m), e_original_m=float(self.params.e_original_m),
                         forward_calls=int(self.forward_calls), queries=int(self.queries),
                         iterations_scored=int(self.iterations_scored))


@dataclass(frozen=True)
class Table3Row:
    """The paper's Table 3 columns of one optimisation and what was measured beside them: kind; threshold_m t
    (m); offset_rate_pct (% of viewpoints moved); position_offset_m (sum of |dp|, m); rotation_offset_deg (sum
    of |dyaw|, deg); time_s (the optimiser's own, s); viewpoints, moved (counts); surrogate_error_m (the moved
    path's predicted error, m); e_original_m (m); forward_calls, queries, iterations_scored (the surrogate's
    work); oracle_confirm_s (s; None: no oracle confirmation ran); oracle_error_m (m; None: not scored);
    oracle (the oracle's verdict on the moved path; None: not scored). wrp_metrics.json's ``table3``."""

    kind: str
    threshold_m: float
    offset_rate_pct: float
    position_offset_m: float
    rotation_offset_deg: float
    time_s: float
    viewpoints: int
    moved: int
    surrogate_error_m: float
    e_original_m: float
    forward_calls: int
    queries: int
    iterations_scored: int
    oracle_confirm_s: float | None = None
    oracle_error_m: float | None = None
    oracle: dict | None = None

    def to_json_dict(self) -> dict:
        """The row as stored (no oracle_confirm_s / oracle key where there is none)."""
        doc = {f.name: getattr(self, f.name) for f in fields(self)}
        for optional in ("oracle_confirm_s", "oracle"):
            if doc[optional] is None:
                del doc[optional]
        return doc

    @classmethod
    def from_json_dict(cls, doc: dict) -> "Table3Row":
        return cls(**{f.name: doc[f.name] for f in fields(cls) if f.name in doc})


def stage_one(query: ViewQuery, view: int, params: WrpParams, seed: int, block: int):
    """Iterations of ``block`` of viewpoint ``view``: their draws and Alg. 4's best yaw, then stage 1 (Alg. 3
    line 9) and feasibility. Returns (first iteration index, draws, positions (c, 3), best yaw (c,), E (c,),
    indices of the survivors in ascending order)."""
    lo = block * params.block_iterations
    count = min(params.block_iterations, params.iterations - lo)
    d = iteration_draws(seed, view, block, params)
    pos, yaws = d.position[:count], d.yaw[:count]
    yaw_best, e1 = best_attitude(query, view, pos, yaws)
    ok = (np.abs(e1 - params.e_original_m) <= params.threshold_m) & params.feasible(view, pos)
    return lo, d, pos, yaw_best, e1, np.flatnonzero(ok)


def cvar(errors: np.ndarray, alpha: float) -> np.ndarray:
    """(..., M) -> (...) the conditional value at risk: the mean of the worst ceil((1 - alpha) M) errors."""
    m = errors.shape[-1]
    k = max(1, int(np.ceil((1.0 - alpha) * m - 1e-9)))
    return np.sort(errors, axis=-1)[..., m - k:].mean(axis=-1)


def neighbourhood_score(errors: np.ndarray, params: WrpParams) -> np.ndarray:
    """(..., M) sample errors -> (...) what ``acceptance: improve | validated`` minimises: the mean error of the
    neighbourhood (ISWRP: the error expected under the wind; its CVaR with ``risk_measure: cvar``) or its
    spread (SWRP, as the statistic)."""
    if params.kind == "iswrp":
        return cvar(errors, params.cvar_alpha) if params.risk_measure == "cvar" else errors.mean(axis=-1)
    return neighbourhood_statistic(errors, params)


def optimise_view_improve(query: ViewQuery, view: int, params: WrpParams,
                          seed: int) -> tuple[int, np.ndarray, float, float, int]:
    """``acceptance: improve | validated``: every iteration passes stage 1; of the survivors, the
    ``improve_candidates`` with the lowest stage-1 error (ties: earlier iteration) get the stage-2 neighbourhood,
    and the one with the best :func:`neighbourhood_score` among those passing stage 2 is kept when it beats the
    unmoved viewpoint's score (a neighbourhood draw around offset 0) by :meth:`WrpParams.improvement_margin_m`.
    Same return as :func:`optimise_view`."""
    b = params.block_iterations
    n_blocks = -(-params.iterations // b)
    t = params.threshold_m
    parts, draws = [], []                        # per block: survivors' iteration, position, yaw, E; its draws
    scored = 0
    for block in range(n_blocks):
        lo, d, pos, yaw_best, e1, survivors = stage_one(query, view, params, seed, block)
        scored += len(pos)
        parts.append((lo + survivors, pos[survivors], yaw_best[survivors], e1[survivors]))
        draws.append(d)
    it, pos, yaw, e1 = (np.concatenate(column) for column in zip(*parts, strict=True))
    if it.size == 0:
        return -1, np.zeros(4), float("nan"), float("nan"), scored
    pick = np.lexsort((it, e1))[:params.improve_candidates]        # lowest E first, ties: earlier iteration
    # only the picked candidates' neighbourhoods are read: a block's neighbour yaws (its largest draw, made on
    # first use) are drawn for the blocks that hold one
    block_of, row = np.divmod(it[pick], b)
    n_off = np.stack([draws[k].neighbour_offset[r] for k, r in zip(block_of, row, strict=True)])
    n_yaw = np.stack([draws[k].neighbour_yaw[r] for k, r in zip(block_of, row, strict=True)])
    # the unmoved viewpoint's neighbourhood (its own stream: block index n_blocks) scored with the candidates
    home = iteration_draws(seed, view, n_blocks, params)
    centres = np.concatenate([home.neighbour_offset[:1], pos[pick][:, None, :] + n_off])   # (1 + k, M, 3)
    yaws = np.concatenate([home.neighbour_yaw[:1], n_yaw])
    _, ek = best_attitude(query, view, centres, yaws)
    stat = neighbourhood_statistic(ek, params)
    score = neighbourhood_score(ek, params)
    home_score, stat, score = score[0], stat[1:], np.where(stat[1:] <= t, score[1:], np.inf)
    k = int(np.argmin(score))
    if np.isfinite(score[k]) and score[k] < home_score - params.improvement_margin_m():
        j = pick[k]
        return int(it[j]), np.array([*pos[j], yaw[j]]), float(e1[j]), float(stat[k]), scored
    return -1, np.zeros(4), float("nan"), float("nan"), scored


def optimise_view(query: ViewQuery, view: int, params: WrpParams,
                  seed: int) -> tuple[int, np.ndarray, float, float, int]:
    """Alg. 3 for one viewpoint against ``query``'s base. Returns (accepted iteration or -1, offset (4,),
    stage-1 error, stage-2 statistic, iterations scored)."""
    if params.acceptance in ("improve", "validated"):
        return optimise_view_improve(query, view, params, seed)
    b = params.block_iterations
    n_blocks = -(-params.iterations // b)
    t = params.threshold_m
    scored = 0
    for block in range(n_blocks - 1, -1, -1):
        lo, d, pos, yaw_best, e1, survivors = stage_one(query, view, params, seed, block)
        scored += len(pos)
        survivors = survivors[::-1]  # latest first
        for s in range(0, survivors.size, params.stage2_batch):
            chunk = survivors[s:s + params.stage2_batch]
            centres = pos[chunk][:, None, :] + d.neighbour_offset[chunk]  # (c, M, 3)
            _, ek = best_attitude(query, view, centres, d.neighbour_yaw[chunk])
            stat = neighbourhood_statistic(ek, params)
            ok = np.flatnonzero(stat <= t)
            if ok.size:
                j = int(chunk[ok[0]])
                offset = np.array([*pos[j], yaw_best[j]])
                return lo + j, offset, float(e1[j]), float(stat[ok[0]]), scored
    return -1, np.zeros(4), float("nan"), float("nan"), scored


def interval_optimise(surrogate: Surrogate, params: WrpParams, seed: int = 0) -> WrpResult:
    """Alg. 3 over every viewpoint of the surrogate's path, in path order."""
    start = time.perf_counter()
    n = surrogate.n_views
    if np.asarray(params.sample_radius_m).shape != (n,):
        raise ValueError(f"sample_radius_m must have one radius per viewpoint ({n})")
    offsets = np.zeros((n, 4))
    moved = np.zeros(n, bool)
    accepted = np.full(n, -1)
    e1 = np.full(n, np.nan)
    stat = np.full(n, np.nan)
    query = ViewQuery(surrogate, offsets)
    scored = 0
    for i in range(n):
        j, off, err, st, k = optimise_view(query, i, params, seed)
        scored += k
        if j >= 0:
            offsets[i], moved[i], accepted[i], e1[i], stat[i] = off, True, j, err, st
            query.update_view(i, off)
    predicted = float(surrogate.predict(offsets[None])[0])
    return WrpResult(offsets, moved, accepted, e1, stat, predicted, time.perf_counter() - start,
                     query.forward_calls, query.queries, params, scored)


def offset_totals(offsets: np.ndarray) -> tuple[float, float]:
    """The paper's position / rotation offset columns (Table 3-5) of offsets (n, 4): sum over viewpoints of
    |dp| (m) and of |dyaw| (deg)."""
    return (float(np.linalg.norm(offsets[:, :3], axis=1).sum()), float(np.degrees(np.abs(offsets[:, 3])).sum()))


def apply_offsets(path, offsets: np.ndarray, note: dict | None = None):
    """The WRP: ``path`` (a :class:`wrp_eval.planning.path.FlightPath`) with positions + offsets[:, :3] and
    yaw + offsets[:, 3] (wrapped to (-pi, pi])."""
    yaw = np.angle(np.exp(1j * (np.asarray(path.yaw) + offsets[:, 3])))
    meta = {**path.metadata, **(note or {})}
    return replace(path, positions=np.asarray(path.positions) + offsets[:, :3], yaw=yaw, metadata=meta)


def offset_cholesky(deviation: np.ndarray, floor_m: float = 1e-3) -> np.ndarray:
    """Per viewpoint the Cholesky factor (n, 3, 3) m of the position-offset covariance over a campaign's
    trials (deviation (n_trials, n_views, 4), NaN where a view was not taken), with ``floor_m``^2 added on the
    diagonal (a view flown identically in every trial still gets a proper, tiny neighbourhood)."""
    pos = np.asarray(deviation, dtype=float)[..., :3]
    ok = np.all(np.isfinite(pos), axis=-1)
    count = ok.sum(axis=0)
    filled = np.where(ok[..., None], pos, 0.0)
    mean = filled.sum(axis=0) / np.maximum(count, 1)[:, None]
    centred = np.where(ok[..., None], pos - mean, 0.0)
    cov = np.einsum("tvi,tvj->vij", centred, centred) / np.maximum(count - 1, 1)[:, None, None]
    return np.linalg.cholesky(cov + floor_m ** 2 * np.eye(3))


def sample_radii(deviation: np.ndarray, quantile: float) -> np.ndarray:
    """r_s per viewpoint from a campaign's wind-induced offsets (n_trials, n_views, 4): the ``quantile`` of
    |flown - commanded| (position part, m) over the trials where the view was taken."""
    norm = np.linalg.norm(deviation[..., :3], axis=-1)
    return np.nanquantile(norm, quantile, axis=0)
