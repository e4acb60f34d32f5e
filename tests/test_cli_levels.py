"""`fembem solve` with levels: adaptive runs (`[adapt] steps`) write one record per level
into summary.json and adapt.csv / adapt.png (nested runs write levels.csv:
tests/test_nested.py); adaptive runs, and plain ones with `[output] estimator`,
report the a posteriori estimator, and with `[data] exact` the energy error;
`[output] indicators` puts eta_T per cell into fields.npz; bad combinations are refused
with one line."""
from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from conftest import load_config, run_cli

CONFIG = load_config(
    'shape = "lshape"\nh = 0.015625\nsubdomain_size = 0.0625\nsignorini = ["bottom"]'
)

#: u = r^(2/3) sin(2 theta/3) at the re-entrant corner (tests/test_adapt.py, CORNER) with
#: u_e = 0: u0 = u, t0 = grad u . n = -(2/3) r^(-1/3) (cos(theta/3) nx + sin(theta/3) ny),
#: theta = atan2(x - y, -(x + y)) + 3 pi/4; linear material, f = 0 (u is harmonic).
U = "(x**2 + y**2)**(1/3)*cos(2/3*atan2(x - y, -(x + y)))"
THETA = "(atan2(x - y, -(x + y)) + 3*pi/4)"
CORNER_CONFIG = f"""
[geometry]
shape = "lshape"
h = 0.0625
subdomain_size = 0.125
[data]
u0 = "{U}"
t0 = "-2/3*(x**2 + y**2)**(-1/6)*(cos({THETA}/3)*nx + sin({THETA}/3)*ny)"
exact = "{U}"
"""


@pytest.fixture
def config(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text(CONFIG)
    return path


def test_adaptive_run_writes_its_levels(config, tmp_path):
    out = tmp_path / "out"
    proc = run_cli("solve", str(config), "--out", str(out), "--quiet", "--set", "adapt.steps=2")
    assert proc.returncode == 0, proc.stderr
    summary = json.loads((out / "summary.json").read_text())
    levels = summary["levels"]
    assert len(levels) == 3
    dofs = [lv["dofs"] for lv in levels]
    assert dofs == sorted(dofs) and dofs[0] < dofs[-1]
    assert all(lv["converged"] for lv in levels)
    assert summary["dofs"] == dofs[-1] and summary["estimator"] == levels[-1]["estimator"]
    assert levels[-1]["estimator"] < levels[0]["estimator"]
    with open(out / "adapt.csv") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["dofs"]) for r in rows] == dofs
    assert "error" not in rows[0] and "error" not in summary  # no exact solution given
    files = set(summary["files"])
    assert {"adapt.csv", "adapt.png"} <= files and "levels.csv" not in files
    assert "indicators" not in np.load(out / "fields.npz").files  # off by default


def test_adaptive_run_with_an_exact_solution_reports_errors_and_indicators(tmp_path):
    """The corner singularity: error and efficiency per level in summary.json and
    adapt.csv; the indicators of fields.npz follow its triangles (the largest at the
    corner) and their squares sum to eta^2."""
    config = tmp_path / "corner.toml"
    config.write_text(CORNER_CONFIG)
    out = tmp_path / "out"
    sets = ["adapt.steps=5", "output.indicators=true", "output.xdmf=false"]
    proc = run_cli("solve", str(config), "--out", str(out), "--quiet", *(
        a for s in sets for a in ("--set", s)
    ))  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    summary = json.loads((out / "summary.json").read_text())
    levels = summary["levels"]
    errors = [lv["error"] for lv in levels]
    assert summary["error"] == errors[-1]
    # measured 0.065 at 65 dofs .. 0.016 at 573 dofs, about N^(-0.58)
    assert all(b < a for a, b in zip(errors, errors[1:])) and errors[-1] < errors[0] / 3
    for lv in levels:
        assert lv["efficiency"] == pytest.approx(lv["estimator"] / lv["error"], rel=1e-12)
        assert 1.0 <= lv["efficiency"] <= 10.0  # measured 3.2 .. 3.5
    with open(out / "adapt.csv") as f:
        rows = list(csv.DictReader(f))
    assert [float(r["error"]) for r in rows] == errors
    fields = np.load(out / "fields.npz")
    eta = fields["indicators"]
    assert eta.shape == (len(fields["triangles"]),) and eta.min() >= 0.0
    assert np.sqrt(np.sum(eta**2)) == pytest.approx(summary["estimator"], rel=1e-12)
    corner = np.flatnonzero(np.linalg.norm(fields["x"], axis=1) < 1e-12)
    assert np.isin(corner, fields["triangles"][np.argmax(eta)]).all()


def test_a_plain_run_reports_the_estimator_when_asked(config, tmp_path):
    """Off by default (no estimator stage, nothing in summary.json); `[output] estimator`
    reports eta, and `indicators` (which implies it) eta_T per cell, the same eta."""
    etas = {}
    for sets in ([], ["output.estimator=true"], ["output.indicators=true"]):
        out = tmp_path / f"out{len(etas)}"
        args = [a for s in ["output.plots=false", *sets] for a in ("--set", s)]
        proc = run_cli("solve", str(config), "--out", str(out), "--quiet", *args)
        assert proc.returncode == 0, proc.stderr
        summary = json.loads((out / "summary.json").read_text())
        assert "levels" not in summary
        assert not {"levels.csv", "adapt.csv", "adapt.png"} & set(summary["files"])
        etas[tuple(sets)] = summary.get("estimator")
        assert ("estimator" in summary["timings"]) == bool(sets)
    assert etas[()] is None
    eta = etas[("output.estimator=true",)]
    assert eta > 0 and etas[("output.indicators=true",)] == pytest.approx(eta, rel=1e-12)
    cells = np.load(out / "fields.npz")["indicators"]
    assert np.sqrt(np.sum(cells**2)) == pytest.approx(eta, rel=1e-12)


@pytest.mark.parametrize(
    "sets,fragment",
    [
        (["adapt.max_dofs=100"], "adapt.max_dofs = 100 is below the starting mesh's 833 dofs"),
        (["solver.nested=true"], "solver.nested = true and adapt.steps > 0 do not combine"),
        (["data.exact=sin(x"], "data.exact:"),
        (["output.indicators=1"], "output.indicators must be true or false"),
    ],
)
def test_bad_level_settings_are_refused(config, tmp_path, sets, fragment):
    out = tmp_path / "out"
    args = [a for s in ["adapt.steps=2", *sets] for a in ("--set", s)]
    proc = run_cli("solve", str(config), "--out", str(out), *args)
    assert proc.returncode == 2
    (line,) = proc.stderr.strip().splitlines()
    assert fragment in line and not out.exists()


def test_an_adaptive_run_reports_every_level(config, tmp_path):
    """Issue 66, item 7: the final line spoke of the last level only ("converged after 2
    iterations"); it now gives the iterations of every level and their total."""
    out = tmp_path / "out"
    proc = run_cli("solve", str(config), "--out", str(out), "--set", "adapt.steps=2")
    assert proc.returncode == 0, proc.stderr
    counts = [lv["iterations"] for lv in json.loads((out / "summary.json").read_text())["levels"]]
    last = proc.stdout.strip().splitlines()[-1]
    assert last.startswith(f"fembem: converged after {counts[-1]} iterations on the final level")
    total = (
        f"{sum(counts)} iterations in all over 3 adaptive levels ({' + '.join(map(str, counts))})"
    )
    assert total in last, last


def test_history_figure_shows_the_levels():
    """history.png of a run over several levels: the final level's convergence with
    integer ticks and a legend entry for each curve drawn, and each level's iterations
    with their total beneath."""
    from types import SimpleNamespace

    import matplotlib.pyplot as plt

    from coupling.io.history_figure import figure_history
    from coupling.io.plots import history_arrays

    records = [  # two iterations, J_h at its lowest from the second on
        SimpleNamespace(iteration=k, energy=e, step_norm=s, contact=c)
        for k, e, s, c in ((1, -0.5, 1e-3, 4), (2, -0.6, 1e-9, 4))
    ]
    levels = [{"dofs": n, "iterations": k} for n, k in ((65, 10), (105, 3), (179, 2))]
    fig = figure_history(history_arrays(records, 1e-9, levels, adaptive=True), 1e-8)
    try:
        top, contact, per_level = fig.axes
        assert "15 iterations in all over 3 adaptive levels" in top.get_title()
        labels = [t.get_text() for t in top.get_legend().get_texts()]
        assert len(labels) == len(top.get_lines())  # every entry is a curve drawn
        fig.canvas.draw()
        for axis in (contact.xaxis, contact.yaxis):
            ticks = [t for t in axis.get_ticklocs() if t == t]
            assert all(float(t).is_integer() for t in ticks), ticks
        assert [p.get_height() for p in per_level.patches] == [10, 3, 2]
        assert [t.get_text() for t in per_level.get_xticklabels()] == ["65", "105", "179"]
    finally:
        plt.close(fig)
    plain = figure_history(history_arrays(records, 1e-9), 1e-8)
    assert len(plain.axes) == 2 and plain.axes[0].get_title() == "Convergence (2 iterations)"
    plt.close(plain)
