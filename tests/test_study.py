"""``python -m study --quick``: the files are produced, linked and sane (study/).

The quick study runs once for the module (about a minute on 2 cores). The checks are
on the figures' meaning, not on fixed numbers: iteration counts positive and below
their cap, bounded at fixed d/h, growing without a preconditioner; eigenvalues
positive and finite; orders of convergence between 0.5 and 3; the reference kappa of
docs/method.md section 6 recomputed; the two Jacobians giving the same iterates.
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

import study

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def out(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("study")
    assert study.main(["--quick", "--out", str(folder)]) == 0
    return folder


def table(out: Path, name: str) -> list[dict]:
    rows = study.read_csv(out / f"{name}.csv")
    assert rows, f"{name}.csv is empty"
    return rows


def test_every_part_writes_linked_tables_and_plots(out):
    readme = (out / "README.md").read_text()
    for part in study.PARTS:
        page = out / f"{part}.md"
        assert page.exists() and f"]({part}.md)" in readme
        text = page.read_text()
        linked = re.findall(r"\]\(([^)]+\.(?:csv|png))\)", text)
        assert any(f.endswith(".csv") for f in linked) and any(f.endswith(".png") for f in linked)
        for file in linked:
            assert (out / file).stat().st_size > 0, file
        # provenance: machine, versions, commit and command on every page
        for needle in (
            "| Machine |",
            "dolfinx",
            "petsc4py",
            "numpy",
            "scipy",
            "git commit",
            "python -m study --quick",
        ):
            assert needle in text, (part, needle)
    assert "## Discussion" in readme and (out / "study.json").exists()


def test_iteration_counts_positive_below_cap_and_bounded(out):
    rows = table(out, "iterations")
    for r in rows:
        assert r["converged"] and 0 < r["iterations"] < r["max_iterations"], r
    methods = {r["method"] for r in rows}
    assert {"pgpm"} <= methods
    for method in methods:
        sub = [
            r
            for r in rows
            if r["preconditioner"] == "substructuring"
            and r["varies"] == "h"
            and r["method"] == method
        ]
        counts = [r["iterations"] for r in sub]
        # Theorem 4.1 (bounded at fixed d/h); 1.5 leaves room for the pre-asymptotic
        # coarsest mesh (the full study measures 1.13 for PGPM over cells 32..512)
        assert len(counts) >= 4 and max(counts) / min(counts) < 1.5, (method, counts)
    ratio = [r for r in rows if r["varies"] == "d/h" and r["method"] == "pgpm"]
    assert all(a["iterations"] < b["iterations"] for a, b in zip(ratio, ratio[1:]))
    identity = [r["iterations"] for r in rows if r["preconditioner"] == "identity"]
    assert identity[1] / identity[0] > 2.5, identity  # Remark 2.1: ~ h^-2
    summary = study.summarize_iterations({"iterations": rows})
    fits = [s["fit"] for s in summary["series"].values() if "fit" in s]
    assert fits and all(math.isfinite(f["C"]) and f["C"] > 0 for f in fits)


def test_spectra_are_positive_and_match_the_reference(out):
    for r in table(out, "spectrum"):
        assert 0 < r["lambda_min"] < r["lambda_max"] < 100 and math.isfinite(r["kappa"])
        if r["dense_check"] is not None:  # Lanczos against a dense eigensolver
            assert r["dense_check"] < 1e-6, r
    for r in table(out, "reference"):
        # docs/method.md quotes kappa to 3 significant digits
        assert abs(r["rel_difference"]) < 2e-3, r
    cond = [r for r in table(out, "cond_ms") if r["series"].startswith("d/h")]
    assert all(a["cond"] < b["cond"] for a, b in zip(cond, cond[1:]))  # grows as h -> 0
    for r in table(out, "rates"):
        assert 0 < r["q_observed_late"] < 1 and 0 < r["q_predicted_face"] < 1
        # the asymptotic contraction is the one the spectrum predicts (within 1 %)
        assert abs(r["q_observed_late"] - r["q_predicted_face"]) < 0.01, r


def test_projection_variants_reach_the_exact_projection_solution(out):
    for r in table(out, "projection"):
        assert r["converged"] and r["outer_iterations"] > 0
        # tol = 1e-8 on the B-norm step bounds the error by ~ kappa * tol (kappa < 100)
        assert r["u_rel_diff_to_exact"] < 1e-5, r


def test_discretisation_orders_are_sane(out):
    rows = table(out, "errors")
    for r in rows:
        assert r["converged"]
        for key in study.ERROR_KEYS:
            order = r[f"order_{key}"]
            if order is not None:
                assert 0.5 < order < 3.0, (r["shape"], r["material"], r["cells"], key, order)
    energy = [r["order_energy"] for r in rows if r["order_energy"] is not None]
    assert np.min(energy) > 0.9  # claim 7.5: O(h) in the energy norm


def test_jacobians_give_identical_iterates(out):
    for r in table(out, "jacobians"):
        assert r["matrix_rel_diff"] < 1e-12
        assert r["iterations_ufl"] == r["iterations_handwritten"]
        assert r["max_rel_energy_diff"] < 1e-12 and r["u_rel_diff"] < 1e-10
    edge = table(out, "edge_forms")
    assert {r["edge_form"] for r in edge} == {"paper", "sqrt-laplacian"}
    assert all(r["converged"] and r["kappa"] > 1 for r in edge)


def test_readme_is_regenerated_from_the_files(out):
    (out / "README.md").unlink()
    assert study.main(["--readme", "--out", str(out)]) == 0
    assert "## Discussion" in (out / "README.md").read_text()


def test_bad_arguments_exit_with_usage_error():
    with pytest.raises(SystemExit) as err:
        study.main(["--only", "nonsense"])
    assert err.value.code == 2
    with pytest.raises(ValueError, match="unknown solver option"):
        study.check_solver_fields({"no_such_option": 1})
