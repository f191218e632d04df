"""Regression figures shared by the training and the diagnostics."""

from __future__ import annotations

import numpy as np


def regression_metrics(y_true: np.ndarray, y_pred: np.ndarray) -> dict:
    """R^2 (coefficient of determination), RMSE and MAE (units of y), n."""
    y_true, y_pred = np.asarray(y_true, float), np.asarray(y_pred, float)
    resid = y_true - y_pred
    ss_tot = float(((y_true - y_true.mean()) ** 2).sum()) if y_true.size else 0.0
    r2 = 1.0 - float((resid ** 2).sum()) / ss_tot if ss_tot > 0 else float("nan")
    return {"r2": r2, "rmse": float(np.sqrt((resid ** 2).mean())) if resid.size else float("nan"),
            "mae": float(np.abs(resid).mean()) if resid.size else float("nan"), "n": int(y_true.size)}
