"""The programs of a run as MLflow shows them: `programs.json`, one row per sample (evaluated,
failed, duplicate or unusable; not the spec's starter) with the columns of `PROGRAM_COLUMNS` and
the code in full, registered as an MLflow table; and the page `programs.html` with the same rows,
best first, each program's code laid out as code (the UI's table view cuts cells to one line; it
renders an HTML artifact as a page)."""

from __future__ import annotations

import html
from typing import Any, Sequence

from colmo.record import SampleRecord

PROGRAMS_TABLE = "programs.json"
PROGRAMS_PAGE = "programs.html"
# The UI shows a table's first columns: score and code first, bookkeeping last.
PROGRAM_COLUMNS = ("sample", "score", "heldout_score", "status", "code", "failure", "island", "batch", "key", "params", "parents", "generator")

def program_row(record: SampleRecord) -> dict[str, Any]:
    """One sample as a row of the programs table (its held-out score is filled in at the end)."""
    return {
        "sample": record.sample, "score": record.score, "heldout_score": record.heldout_score, "status": record.status,
        "code": record.code, "failure": record.failure, "island": record.island, "batch": record.batch,
        "key": record.key, "params": record.params, "parents": record.parent_keys, "generator": record.generator,
    }


def programs_page(rows: Sequence[dict[str, Any]], title: str) -> str:
    """The programs as an HTML page: evaluated ones best first, then the rest by sample, each
    with its code in full."""
    ordered = sorted(rows, key=lambda r: (r["score"] is None, -(r["score"] or 0.0), r["sample"]))
    number = lambda value: "" if value is None else f"{value:.2f}"  # noqa: E731
    cells = []
    for row in ordered:
        code = html.escape(row["code"] or "")
        failure = html.escape(row["failure"] or "")
        cells.append(
            f"<tr><td>{row['sample']}</td><td>{number(row['score'])}</td><td>{number(row['heldout_score'])}</td>"
            f"<td>{row['status']}</td><td>{row['island']}</td><td>{html.escape(row['generator'])}</td><td><pre>{code}</pre>{failure}</td></tr>"
        )
    style = "body{font-family:sans-serif;font-size:13px}td{vertical-align:top;border-top:1px solid #ddd;padding:4px 8px}pre{margin:0}"
    return (
        f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title><style>{style}</style></head><body>"
        f"<h3>{html.escape(title)}: {len(rows)} samples, best first</h3><table><tr><th>sample</th><th>score</th>"
        f"<th>held-out</th><th>status</th><th>island</th><th>generator</th><th>code / failure</th></tr>{''.join(cells)}</table></body></html>"
    )
