"""The interface every part of the study has: the :class:`Table` it returns and the
:class:`Part` record that names its four functions."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Sequence

__all__ = ["Table", "Part", "Tables", "Figures"]

#: The tables of a part by name, each a list of rows (dicts), as read back from CSV.
Tables = dict[str, list[dict[str, Any]]]
#: The figures of a part: (PNG file name, caption).
Figures = list[tuple[str, str]]


@dataclass
class Table:
    """One table of a part: its rows, a title, what it shows, and the columns shown
    in markdown (the CSV file has all columns)."""

    name: str
    title: str
    description: str
    rows: list[dict[str, Any]]
    columns: Sequence[str]


@dataclass(frozen=True)
class Part:
    """One part of the study; every part module defines ``PART`` with these fields.

    ``run(comm, sizes)`` computes the tables (the only step that solves anything);
    ``summarize(tables)`` derives the numbers the page and the README quote, from the
    tables alone (so that the README can be rebuilt from the CSV files);
    ``plot(tables, writer)`` draws the figures; ``summary_markdown(summary)`` is the
    page's table of derived numbers. The README's prose on the part is in
    :mod:`study.discussion`.
    """

    name: str
    title: str
    intro: str
    run: Callable[..., list[Table]]
    summarize: Callable[[Tables], dict[str, Any]]
    plot: Callable[[Tables, Any], Figures]
    summary_markdown: Callable[[dict[str, Any]], str]
