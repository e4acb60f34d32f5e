"""Shared test helpers: running scripts under mpirun, the benches, the project root."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
#: [material] and [data] of the tests' load case: carstensen, f = 1 + x, t0 = -1, u0 = 0.1
#: materials the form and material tests run through: (rho, its parameters)
TEST_MATERIALS = [
    ("linear", {}),
    ("carstensen", {}),
    ("power", {"p": 1.5, "eps": 0.1}),
    ("power", {"p": 3.0, "eps": 0.5}),
    ("1 + t^2/(1 + t^2)", {}),
]
LOAD_CASE = '[material]\nrho = "carstensen"\n[data]\nf = "1 + x"\nt0 = "-1"\nu0 = "0.1"\n'


def load_config(geometry: str, **sections: str) -> str:
    """The TOML text of the load case on ``geometry`` (the lines of [geometry]), then the
    ``sections`` (name -> their lines), e.g. ``solver='method = "ssn"'``."""
    text = f"[geometry]\n{geometry}\n{LOAD_CASE}"
    return text + "".join(f"[{name}]\n{lines}\n" for name, lines in sections.items())


def run_bench(script: str, *args: str, timeout: float = 600) -> subprocess.CompletedProcess:
    """Run ``bench/<script> args...`` with this interpreter from the project root, in this
    process's environment (``os.environ``: an MPI-initialised test process has Open MPI
    singleton variables in its C environment that would make the bench's mpirun fail)."""
    return subprocess.run(
        [sys.executable, str(ROOT / "bench" / script), *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=ROOT,
        env=dict(os.environ),
    )


def run_mpi(
    nprocs: int, *args: str, timeout: float = 300, cwd: Path | None = None, check: bool = True
) -> subprocess.CompletedProcess:
    """Run ``python args...`` under ``mpirun -n nprocs`` with this interpreter."""
    mpirun = shutil.which("mpirun")
    if mpirun is None:
        pytest.fail("mpirun not found: `make setup` installs openmpi-bin")
    cmd = [
        mpirun,
        "--allow-run-as-root",
        "--oversubscribe",
        "-n",
        str(nprocs),
        sys.executable,
        *args,
    ]
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    proc = subprocess.run(
        cmd, capture_output=True, text=True, timeout=timeout, cwd=cwd or ROOT, env=env
    )
    if check and proc.returncode != 0:
        pytest.fail(
            f"{' '.join(cmd)} exited {proc.returncode}\nstdout:\n{proc.stdout}\n"
            f"stderr:\n{proc.stderr[-4000:]}"
        )
    return proc


def run_cli(
    *args: str, timeout: float = 300, cwd: Path | None = None
) -> subprocess.CompletedProcess:
    """Run ``fembem args...`` (the installed console script) and capture its output."""
    exe = Path(sys.executable).parent / "fembem"
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "coupling.app.cli"]
    return subprocess.run(
        [*cmd, *args], capture_output=True, text=True, timeout=timeout, cwd=cwd or ROOT
    )


def solved_fields(folder: Path, name: str, text: str) -> dict:
    """``fembem solve`` (quiet, without solution.xdmf and the figures) of the TOML ``text``
    written to ``folder/<name>.toml``, run to success into ``folder/<name>``: its fields.npz
    as a dict."""
    config = folder / f"{name}.toml"
    config.write_text(text + "\n[output]\nxdmf = false\nplots = false\n")
    proc = run_cli("solve", str(config), "--out", str(folder / name), "--quiet")
    assert proc.returncode == 0, proc.stderr
    with np.load(folder / name / "fields.npz") as data:
        return {k: data[k] for k in data.files}


def points_table(command: str, out: Path, csv: Path, text: str) -> list[str]:
    """``fembem COMMAND OUT --points CSV`` (evaluate or exterior) of the points ``text``
    written to ``csv``, run to success: the lines of its table."""
    csv.write_text(text)
    proc = run_cli(command, str(out), "--points", str(csv))
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip().splitlines()


def json_report(command: str, config: Path) -> dict:
    """``fembem COMMAND CONFIG --json`` run to success (exit 0), its JSON report."""
    proc = run_cli(command, str(config), "--json")
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)
