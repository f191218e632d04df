"""``logs/<run>/report.md`` of a study: the table with the paper's figures beside ours, failures, the shared
campaigns, timings and a ship-and-path figure per variant (the run report's helpers in :mod:`wrp_eval.report`)."""

from __future__ import annotations

from pathlib import Path

from wrp_eval.atomic import write_text_atomic
from wrp_eval.report import fmt, ship_path_figure
from wrp_eval.study.config import COLUMNS


def _cell(value, kind: str) -> str:
    """One table cell: None -> '/', text as is, ints as ints, numbers to 4 significant digits."""
    if value is None:
        return "/"
    if kind == "text" or isinstance(value, str):
        return str(value)
    if kind == "int":
        return str(int(value))
    return fmt(value, 4)


def study_table(doc: dict) -> list[str]:
    """Markdown rows of a study: per column, ours then the paper's figure beside it."""
    cols = doc["columns"]
    head = ["variant"]
    for c in cols:
        head += [COLUMNS[c][0], "paper"]
    lines = ["| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
    for row in doc["rows"]:
        name = row["variant"] + (f" #{row['repetition']}" if row.get("repetition") else "")
        cells = [name]
        for c in cols:
            ours = _cell(row["ours"].get(c), COLUMNS[c][1])
            if c == "error_m" and row["ours"].get("failed"):
                ours = f"failed ({ours})"
            paper = row["paper"].get(c)   # the paper's figure verbatim (as the config gives it)
            cells += [ours, ("/" if paper is None else str(paper)) if c in row["paper"] else ""]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def write_study_report(out: Path, doc: dict, figures: list) -> Path:
    """``out/report.md`` of a study (``wrp_eval.study``): the table with the paper's figures beside ours, where
    each variant failed and why, the shared campaigns, the timings and a ship-and-path figure per variant.
    figures: [(variant name, path, resolved ship, variant folder)]."""
    heading = f"Table {doc['table']}" if doc.get("table") else "Study"
    lines = [
        f"# wrp-eval study `{doc['run']}`: {heading}" + (f" — {doc['title']}" if doc.get("title") else ""),
        "",
        f"Config `{doc['config']}`, seed {doc['seed']}" + (" (smallest setting)" if doc.get("smallest") else "")
        + ". Each variant's column pair shows ours, then the paper's figure. The paper's figures are anchors from "
        "another system (Unity scene, ContextCapture errors on another scale, a Xeon + RTX 3090), not targets: "
        "ours are what this run measured. Reconstruction error: the configured oracle on the path flown exactly "
        "as planned (or as offset), in metres; 'failed' is the oracle's verdict.",
        "",
        *study_table(doc),
        "",
    ]
    failed = [r for r in doc["rows"] if r["ours"].get("failed")]
    if failed:
        lines += ["Failed reconstructions:", ""]
        lines += [f"- {r['variant']}" + (f" #{r['repetition']}" if r.get("repetition") else "")
                  + f": {r['ours'].get('reason', '')}" for r in failed]
        lines.append("")
    if doc.get("shared_training"):
        lines += ["## Campaigns and surrogates", "", "| key | campaign | trials (failed) | campaign (s) | "
                  "surrogate R^2 / RMSE (m) |", "|---|---|---|---|---|"]
        for key, t in doc["shared_training"].items():
            test = t.get("surrogate_test") or {}
            lines.append(f"| {key} | `{t['campaign']}` | {t['trials']} ({t['failed']}) | {t['campaign_s']:.1f} | "
                         f"{fmt(test.get('r2'))} / {fmt(test.get('rmse'))} |")
        lines.append("")
    if figures:
        lines += ["## Paths", ""]
        for name, path, ship, folder in figures:
            png = ship_path_figure(ship.mesh, path, Path(folder) / "path.png")
            lines += [f"{name}:", "", f"![{name}]({png.relative_to(out)})", ""]
    lines += ["## Timings (s)", "", "| variant | wall (s) |", "|---|---|"]
    lines += [f"| {k} | {v:.1f} |" for k, v in doc["timings_s"].items()]
    lines.append("")
    return write_text_atomic(out / "report.md", "\n".join(lines))
