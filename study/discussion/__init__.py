"""The generated discussion of the study's README: the claims table, the departures
from the paper (:mod:`~study.discussion.claims`) and one section per part
(:mod:`~study.discussion.sections`), every number read from the parts'
summaries (the CSV files) and every verdict from the criterion printed next to it."""
from __future__ import annotations

from typing import Any

from study.discussion.adaptivity import discuss_adaptivity
from study.discussion.claims import claims_table, departures
from study.discussion.sections import (
    discuss_errors,
    discuss_iterations,
    discuss_methods,
    discuss_projection,
    discuss_spectrum,
    discuss_variants,
)

__all__ = ["discussion"]

Summaries = dict[str, dict[str, Any]]


def discussion(summaries: Summaries) -> str:
    """The discussion of the README; every number is taken from ``summaries`` (the CSV
    files of the parts), every verdict from the criterion stated next to it."""
    out = [
        "## Discussion",
        "",
        "The numbers below are read from the CSV files of the parts listed above; each "
        "part's page names the run (command, commit, start time) that produced it.",
        "",
        "### The claims at a glance",
        "",
        *claims_table(summaries),
        "",
    ]
    departed = departures(summaries)
    if departed:
        out += ["### Where the measurements depart from the paper", "", *departed, ""]
    if "iterations" in summaries:
        out += discuss_iterations(summaries["iterations"], summaries.get("spectrum"))
        out += discuss_methods(summaries["iterations"])
    if "spectrum" in summaries:
        out += discuss_spectrum(summaries["spectrum"])
    if "projection" in summaries:
        out += discuss_projection(summaries["projection"])
    if "errors" in summaries:
        out += discuss_errors(summaries["errors"])
    if "variants" in summaries:
        out += discuss_variants(summaries["variants"])
    if "adaptivity" in summaries:
        out += discuss_adaptivity(summaries["adaptivity"])
    return "\n".join(out)
