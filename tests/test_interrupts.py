"""Interrupts (SIGINT, SIGTERM) at each stage of `fembem solve`, serial and under mpirun:
one line on stderr, no traceback, exit 130 / 143 (serial), and the output folder holds
the earlier complete run (or nothing) afterwards, with no staging folder left beside it.
Readers refuse a folder without a complete summary.json.
"""
from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import ROOT, load_config, run_cli

FEMBEM = [str(Path(sys.executable).parent / "fembem")]
CONFIG = load_config(
    'h = {h}\nsubdomain_size = {d}\nsignorini = ["bottom"]', solver='method = "pgpm"'
)
#: the stage lines of `fembem solve` (coupling.app.progress) and what follows each
STAGES = {
    "set-up": "fembem: building the mesh",
    "solve": "  it     1 ",
    "outputs": "fembem: writing outputs",
}


def _interrupt(cmd: list[str], marker: str, signum: int) -> tuple[int, str, str]:
    """Start ``cmd``, send ``signum`` once a stdout line starts with ``marker``."""
    proc = subprocess.Popen(
        cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT
    )
    seen = []
    for line in proc.stdout:
        seen.append(line)
        if line.startswith(marker):
            proc.send_signal(signum)
            break
    out, err = proc.communicate(timeout=300)
    return proc.returncode, "".join(seen) + out, err


def _earlier_run(tmp_path: Path) -> Path:
    """An output folder holding a complete earlier run (a marker file inside)."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "marker").write_text("earlier run")
    return out


def _assert_untouched(out: Path) -> None:
    assert sorted(p.name for p in out.iterdir()) == ["marker"]
    assert [p.name for p in out.parent.iterdir() if p.name.startswith(f".{out.name}")] == []


@pytest.mark.parametrize(
    "stage,signum",
    [("set-up", signal.SIGINT), ("solve", signal.SIGTERM), ("outputs", signal.SIGINT)],
)
def test_interrupt_leaves_the_earlier_run(tmp_path, stage, signum):
    config = tmp_path / "c.toml"
    h = 1 / 1024 if stage == "set-up" else 1 / 512  # a set-up long enough to be hit
    config.write_text(CONFIG.format(h=h, d=4 * h))
    out = _earlier_run(tmp_path)
    code, stdout, stderr = _interrupt(
        [*FEMBEM, "solve", str(config), "--out", str(out), "--force"], STAGES[stage], signum
    )
    assert code == {signal.SIGINT: 130, signal.SIGTERM: 143}[signum], stderr
    later = list(STAGES.values())[list(STAGES).index(stage) + 1 :]
    assert not any(marker in stdout for marker in later), "the signal came too late"
    assert "Traceback" not in stderr
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert lines == [
        f"fembem: interrupted by {signal.Signals(signum).name}; " "no output of this run was kept"
    ], stderr
    _assert_untouched(out)


def test_interrupt_without_earlier_run_leaves_nothing(tmp_path):
    config = tmp_path / "c.toml"
    config.write_text(CONFIG.format(h=1 / 512, d=1 / 128))
    out = tmp_path / "new"
    code, _, stderr = _interrupt(
        [*FEMBEM, "solve", str(config), "--out", str(out)], STAGES["solve"], signal.SIGINT
    )
    assert code == 130, stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.toml"]


@pytest.mark.mpi
def test_interrupt_under_mpirun(tmp_path):
    """mpirun forwards the signal to every rank as SIGTERM; each rank cleans up and the
    first to claim the staging folder prints the one line. (mpirun's own exit code for a
    job it aborted is its own: 1.)

    The line reaches the terminal only while mpirun still forwards the ranks' output,
    which it stops soon after it forwards the signal: measured, the line arrives on an
    idle machine and may be lost at load 7 or more on 2 cores. So the test asks for at
    most that one line; the clean-up (no traceback, the earlier run intact, no staging
    folder) must hold whatever the load."""
    mpirun = shutil.which("mpirun")
    config = tmp_path / "c.toml"
    config.write_text(CONFIG.format(h=1 / 512, d=1 / 128))
    out = _earlier_run(tmp_path)
    cmd = [
        mpirun,
        "--allow-run-as-root",
        "--oversubscribe",
        "-n",
        "2",
        *FEMBEM,
        "solve",
        str(config),
        "--out",
        str(out),
        "--force",
    ]
    code, _, stderr = _interrupt(cmd, STAGES["solve"], signal.SIGINT)
    assert code != 0
    assert "Traceback" not in stderr
    lines = [ln for ln in stderr.splitlines() if ln.startswith("fembem:")]
    # issue 29: under mpirun the line says what the user did, not the signal mpirun sent
    assert lines in ([], ["fembem: interrupted; no output of this run was kept"]), stderr
    _assert_untouched(out)


def test_readers_refuse_an_incomplete_folder(tmp_path):
    """A folder with fields.npz but no complete summary.json (say, copied by hand) is
    refused by `exterior` with one line."""
    config = tmp_path / "c.toml"
    config.write_text(CONFIG.format(h=1 / 32, d=1 / 8))
    out = tmp_path / "run"
    assert run_cli("solve", str(config), "--out", str(out), "--quiet").returncode == 0
    points = tmp_path / "p.csv"
    points.write_text("0.6,0.0\n")
    assert run_cli("exterior", str(out), "--points", str(points)).returncode == 0
    summary = json.loads((out / "summary.json").read_text())
    (out / "u.png").unlink()  # a file summary.json lists
    proc = run_cli("exterior", str(out), "--points", str(points))
    assert proc.returncode == 2 and "u.png" in proc.stderr and "not a complete run" in proc.stderr
    (out / "summary.json").write_text(json.dumps(summary)[:-10])  # cut short
    proc = run_cli("exterior", str(out), "--points", str(points))
    assert proc.returncode == 2 and "not a complete summary" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
