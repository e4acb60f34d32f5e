"""The files of the study: one CSV file per table, PNG figures, a markdown page and a
JSON record per part, and the way back from the CSV files to the tables."""
from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any, Sequence

import matplotlib
import numpy as np

from study.base import Table, Tables
from study.provenance import provenance_markdown

matplotlib.use("Agg")  # files only, never a window; before pyplot is imported
import matplotlib.pyplot as plt  # noqa: E402

__all__ = ["ResultWriter", "markdown_table", "read_csv", "load_tables", "format_value"]


def format_value(value: Any) -> str:
    """A table cell: empty for None and nan, yes/no, integers as such, 4 significant
    digits in [1e-3, 1e5), scientific notation outside."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if v == 0.0:
            return "0"
        if 1e-3 <= abs(v) < 1e5:
            return f"{v:.4g}"
        return f"{v:.3e}"
    return str(value)


def markdown_table(rows: Sequence[dict], columns: Sequence[str]) -> str:
    """The ``columns`` of ``rows`` as a markdown table."""
    head = "| " + " | ".join(columns) + " |"
    rule = "|" + "|".join("---" for _ in columns) + "|"
    body = ["| " + " | ".join(format_value(r.get(c)) for c in columns) + " |" for r in rows]
    return "\n".join([head, rule, *body])


def _parse(text: str) -> Any:
    if text == "":
        return None
    if text in ("True", "False"):
        return text == "True"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def read_csv(path: Path) -> list[dict[str, Any]]:
    """Rows of a CSV file written by :meth:`ResultWriter.write_csv`, values typed back."""
    with open(path, newline="") as f:
        return [{k: _parse(v) for k, v in row.items()} for row in csv.DictReader(f)]


def load_tables(out: Path, part: str) -> Tables | None:
    """The tables of ``part`` from its CSV files in ``out`` (None when it has not run)."""
    meta_path = out / f"{part}.json"
    if not meta_path.exists():
        return None
    meta = json.loads(meta_path.read_text())
    tables = {}
    for name in meta["tables"]:
        path = out / f"{name}.csv"
        tables[name] = read_csv(path) if path.exists() and path.stat().st_size else []
    return tables


class ResultWriter:
    """Writes one part: ``<name>.csv`` per table, PNG figures and ``<part>.md``, and
    ``<part>.json`` (provenance, run time, derived numbers) for the README."""

    def __init__(self, out: Path, prov: dict[str, Any]):
        self.out = Path(out)
        self.out.mkdir(parents=True, exist_ok=True)
        self.prov = prov

    @staticmethod
    def subplots(*args: Any, **kwargs: Any) -> tuple[Any, Any]:
        """``matplotlib.pyplot.subplots`` on the file-only backend."""
        return plt.subplots(*args, **kwargs)

    def write_csv(self, table: Table) -> Path:
        path = self.out / f"{table.name}.csv"
        columns: list[str] = []
        for row in table.rows:
            columns += [k for k in row if k not in columns]
        with open(path, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=columns)
            writer.writeheader()
            for row in table.rows:
                writer.writerow({k: ("" if v is None else v) for k, v in row.items()})
        return path

    def save_figure(self, fig: Any, name: str) -> str:
        """Write ``fig`` as ``<name>.png``, close it, return the file name."""
        fig.savefig(self.out / f"{name}.png", dpi=110, bbox_inches="tight")
        plt.close(fig)
        return f"{name}.png"

    def figure(self, fig: Any, name: str, caption: str) -> tuple[str, str]:
        """Write ``fig`` as ``<name>.png`` (:meth:`save_figure`); the (file, caption) entry
        of a part's figure list."""
        return self.save_figure(fig, name), caption

    def write_part(
        self,
        part: str,
        title: str,
        intro: str,
        tables: Sequence[Table],
        figures: Sequence[tuple[str, str]],
        summary: dict[str, Any],
        summary_md: str,
        seconds: float,
    ) -> None:
        sections = [f"# {title}", "", provenance_markdown(self.prov, seconds), "", intro, ""]
        for table in tables:
            self.write_csv(table)
            shown = [markdown_table(table.rows, table.columns), ""] if table.columns else []
            sections += [
                f"## {table.title}",
                "",
                table.description,
                "",
                *shown,
                f"All columns: [{table.name}.csv]({table.name}.csv)",
                "",
            ]
        if summary_md:
            sections += ["## Derived numbers", "", summary_md, ""]
        for file, caption in figures:
            sections += [f"![{caption}]({file})", "", f"*{caption}*", ""]
        (self.out / f"{part}.md").write_text("\n".join(sections))
        meta = {
            "part": part,
            "title": title,
            "seconds": seconds,
            "provenance": self.prov,
            "tables": [t.name for t in tables],
            "figures": [f for f, _ in figures],
            "summary": summary,
        }
        (self.out / f"{part}.json").write_text(json.dumps(meta, indent=1, default=float))
