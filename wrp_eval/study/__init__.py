"""Studies: named variants of an experiment config measured side by side (the paper's Tables 1-8)."""

from wrp_eval.study.config import COLUMNS, StudySection, StudyVariant

__all__ = ["COLUMNS", "StudySection", "StudyVariant"]
