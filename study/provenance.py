"""Where and how a part ran: machine, versions, git commit and command (no value typed
by hand), and its markdown form on every page."""
from __future__ import annotations

import datetime
import os
import platform
import subprocess
import sys
from pathlib import Path
from typing import Any, Sequence

__all__ = ["ROOT", "provenance", "provenance_markdown"]

ROOT = Path(__file__).resolve().parents[1]  # the project (git work tree)


def _git(*args: str) -> str:
    try:
        out = subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, timeout=30)
        return out.stdout.rstrip() if out.returncode == 0 else ""
    except (OSError, subprocess.SubprocessError):
        return ""


def provenance(argv: Sequence[str]) -> dict[str, Any]:
    """Machine, versions, git commit and command of this run (``argv``: the study's
    arguments after ``python -m study``)."""
    import dolfinx
    import matplotlib
    import mpi4py
    import numpy as np
    import petsc4py
    import scipy
    from petsc4py import PETSc

    cpu = platform.processor() or "unknown"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(
                (line.split(":", 1)[1].strip() for line in f if line.startswith("model name")), cpu
            )
    except OSError:
        pass
    changed = [
        line.split(maxsplit=1)[1]
        for line in _git("status", "--porcelain", "--untracked-files=no").splitlines()
        if line.strip()
    ]
    affinity = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None
    return {
        "platform": platform.platform(),
        "cpu": cpu,
        "cores": os.cpu_count(),
        "cores_available": affinity,
        "load_average_at_start": [round(x, 2) for x in os.getloadavg()],
        "python": platform.python_version(),
        "dolfinx": dolfinx.__version__,
        "petsc4py": petsc4py.__version__,
        "petsc": ".".join(str(v) for v in PETSc.Sys.getVersion()),
        "mpi4py": mpi4py.__version__,
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "matplotlib": matplotlib.__version__,
        "git_commit": _git("rev-parse", "HEAD") or "unknown",
        "git_uncommitted_files": changed,
        "command": "python -m study" + "".join(f" {a}" for a in argv),
        "process": " ".join([Path(sys.executable).name] + sys.argv),
        "started": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
    }


def provenance_markdown(prov: dict[str, Any], seconds: float | None = None) -> str:
    """The provenance ``prov`` as a two-column markdown table (with the run time of the
    part, ``seconds``, when given)."""
    changed = prov["git_uncommitted_files"]
    commit = f"`{prov['git_commit']}`"
    if changed:
        commit += (
            f" plus uncommitted changes to {len(changed)} tracked file(s): "
            + ", ".join(f"`{c}`" for c in changed[:12])
            + (" ..." if len(changed) > 12 else "")
        )
    lines = [
        "| | |",
        "|---|---|",
        f"| Machine | {prov['platform']}; CPU {prov['cpu']}; {prov['cores']} cores "
        f"({prov['cores_available']} available); load average at start "
        f"{', '.join(str(x) for x in prov['load_average_at_start'])} |",
        f"| Versions | python {prov['python']}, dolfinx {prov['dolfinx']}, petsc4py "
        f"{prov['petsc4py']} (PETSc {prov['petsc']}), mpi4py {prov['mpi4py']}, numpy "
        f"{prov['numpy']}, scipy {prov['scipy']}, matplotlib {prov['matplotlib']} |",
        f"| Project | git commit {commit} |",
        f"| Command | `{prov['command']}` (process: `{prov['process']}`) |",
        f"| Run | started {prov['started']}"
        + (f"; this part took {seconds:.1f} s" if seconds is not None else "")
        + " |",
    ]
    return "\n".join(lines)
