"""Probe (issue 30 item 1, session 27): does the scarce coverage a view's flown pose takes away help the surrogate as
an input? Offline: reads a stored campaign, trains in this process, writes only OUT_DIR.

    .venv/bin/python scripts/probes/scarce_input.py CAMPAIGN_DIR OUT_DIR [--seeds 0 1 2] [--moves-seeds 0 1]

Per training seed, two surrogates on the same split: ``surrogate.inputs: per_view`` (the default) and ``scarce``
(per_view + :class:`wrp_eval.surrogate.scarce.ScarceCoverage`'s channel). Reported: validation / test R^2 (the held-out
flights that choose inputs) and the single-view agreement with the jitter-averaged oracle on the surrogate bench's
moves (``single_view_agreement``: 200 moves, 4 jitters, forecast blur; the oracle scores computed once per move
seed and shared). The channel's level (c = 2) was picked on the seed-0 moves in session 26; seed 1's are not
those. Writes OUT_DIR/scarce_input.json.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from wrp_eval.surrogate.config import SurrogateSection
from wrp_eval.surrogate.data import load_campaign_trials
from wrp_eval.surrogate.diagnostics import single_view_agreement
from wrp_eval.surrogate.train import train_surrogate

KEYS = ("spearman", "sign_top_decile", "rmse_m", "surrogate_change_std_m", "oracle_change_std_m")


def evaluate(data, folder: str, inputs: str, seed: int, split, oracles: dict) -> tuple[dict, tuple]:
    """Held-out R^2 and the single-view agreement of one training; the oracle scores are filled in ``oracles``."""
    result = train_surrogate(data, SurrogateSection(inputs=inputs), seed=seed, split=split)
    out = {"val_r2": result.metrics["val"]["r2"], "test_r2": result.metrics["test"]["r2"],
           "epochs": result.metrics["epochs_run"], "train_s": result.seconds}
    for moves in sorted(oracles):
        agree = single_view_agreement(result.surrogate, folder, n_moves=200, jitters=4, seed=moves,
                                      oracle=oracles[moves])
        oracles[moves] = agree["oracle"]
        out[f"moves{moves}"] = {k: agree[k] for k in KEYS}
    print(inputs, f"seed {seed}:", json.dumps(out), flush=True)
    return out, tuple(np.asarray(result.split[k], dtype=np.int64) for k in ("train", "val", "test"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("campaign")
    parser.add_argument("out")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--moves-seeds", type=int, nargs="+", default=[0, 1])
    args = parser.parse_args()
    data = load_campaign_trials(args.campaign, scarce=True)
    oracles: dict = {s: None for s in args.moves_seeds}
    result: dict = {}
    for seed in args.seeds:
        plain, split = evaluate(data, args.campaign, "per_view", seed, None, oracles)
        scarce, _ = evaluate(data, args.campaign, "scarce", seed, split, oracles)
        result[f"seed{seed}"] = {"per_view": plain, "scarce": scarce}
        Path(args.out).mkdir(parents=True, exist_ok=True)
        (Path(args.out) / "scarce_input.json").write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
