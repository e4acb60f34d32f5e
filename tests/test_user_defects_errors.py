"""Issue 29, item 1: an exception raised on one rank only ends every rank at once, with
one line naming the rank and a non-zero exit code, and leaves no staging folder."""
from __future__ import annotations

import pytest

from conftest import ROOT, run_mpi

SCRIPT = str(ROOT / "tests" / "mpi" / "inject_failure.py")
CONFIG = """\
[geometry]
h = 0.0625
subdomain_size = 0.125
signorini = ["bottom"]
[adapt]
steps = 2
[output]
plots = false
"""


@pytest.mark.mpi
@pytest.mark.parametrize(
    "where,kind,code,text",
    [
        ("solve", "runtime", 1, "internal error (RuntimeError: injected on rank 1)"),
        ("setup", "value", 2, "injected on rank 1"),
    ],
)
def test_an_exception_on_one_rank_ends_every_rank(tmp_path, where, kind, code, text):
    (tmp_path / "c.toml").write_text(CONFIG)
    proc = run_mpi(
        2,
        SCRIPT,
        "1",
        where,
        kind,
        "solve",
        "c.toml",
        "--out",
        "out",
        cwd=tmp_path,
        timeout=120,  # before issue 29 the other rank waited for ever
        check=False,
    )
    assert proc.returncode == code, proc.stderr[-2000:]
    lines = [ln for ln in proc.stderr.splitlines() if ln.startswith("fembem:")]
    assert len(lines) == 1 and lines[0].startswith(f"fembem: error on rank 1: {text}"), lines
    assert "Traceback" not in proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.toml"]  # no staging folder left
