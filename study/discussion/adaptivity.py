"""The README's section on the adaptivity part (part 6): the targets of issue 19, each
with its measured number and the criterion that decides it."""
from __future__ import annotations

from typing import Any

from study.common import join

__all__ = ["discuss_adaptivity"]


def _verdict(ok: bool) -> str:
    return "met" if ok else "**not met**"


def discuss_adaptivity(ad: dict[str, Any]) -> list[str]:
    """Rates, dofs to reach the uniform error, efficiency band, and the counts per level."""
    series = ad["series"]
    out = ["### Adaptive refinement (part 6)", ""]
    adaptive, uniform = series.get("adaptive, ssn"), series.get("uniform, ssn")
    if adaptive and uniform:
        rate = max(adaptive["error_slope"], adaptive["estimator_slope"])
        fractions = [f["fraction"] for f in ad["dofs_fraction"]]
        half = bool(fractions) and all(f is not None and f <= 0.5 for f in fractions)
        band = max(adaptive["efficiency_band"], uniform["efficiency_band"])
        out += [
            f"- Rates on the singular L-shape (levels with N >= {ad['min_dofs']} when two "
            f"or more are that large): adaptive error {adaptive['error_slope']:.2f} and "
            f"estimator {adaptive['estimator_slope']:.2f}, uniform "
            f"{uniform['error_slope']:.2f} and {uniform['estimator_slope']:.2f} (theory "
            f"-1/2 and -1/3); target slope <= -0.45: {_verdict(rate <= -0.45)}.",
            "- The error of each uniform level after the first is reached with "
            + join(fractions)
            + f" times its dofs; target at most 1/2: {_verdict(half)}.",
            f"- Efficiency index eta / error: adaptive {adaptive['efficiency_min']:.2f} .. "
            f"{adaptive['efficiency_max']:.2f}, uniform {uniform['efficiency_min']:.2f} .. "
            f"{uniform['efficiency_max']:.2f}; target max/min <= 3: {_verdict(band <= 3)}.",
        ]
    for name, s in series.items():
        out.append(
            f"- {name}: outer iterations per level {join(s['iterations'], '{}')}"
            + (
                f" (CG {join(s['cg_iterations'], '{}')})"
                if s["method"] == "ssn"
                else f"; the finest level has d over its smallest cell "
                f"{s['d_over_h_max'][-1]:.0f} and {s['subdomains'][-1]} subdomains of "
                f"diameter / smallest cell at most {s['grading'][-1]:.1f}"
            )
            + "."
        )
    out += [
        "",
        "Local refinement raises the local d/h (a subdomain's diameter over its smallest "
        "cell) inside the subdomains at the corner; Theorem 4.1 bounds the PGPM count by "
        "C (1 + ln(d/h))^2 with that local ratio, so the loop splits every subdomain whose "
        "ratio exceeds twice that of the first mesh (docs/design/adapt.md, 'Subdomains on "
        "graded meshes').",
        "",
    ]
    return out
