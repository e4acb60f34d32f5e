"""Run a ``# %%`` percent script cell by cell, marking where each cell's output ends.

``python run_cells.py SCRIPT ARGS...`` runs SCRIPT with ``sys.argv = [SCRIPT, *ARGS]``
in one namespace, as ``python SCRIPT ARGS...`` would, and after each code cell prints
(on MPI rank 0) a line ``@@cell <index> <figures>@@`` with the PNG files of the
``--out`` folder that the cell wrote or changed (comma-separated). docs/_ext's demo pages
split the output at these lines.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

MARK = "@@cell"


def cells(text: str) -> list[tuple[str, str]]:
    """The (kind, source) cells of a percent script, kind "markdown" or "code"."""
    out: list[tuple[str, str]] = []
    kind, lines = None, []
    for line in text.splitlines():
        if line.startswith("# %%"):
            if kind is not None:
                out.append((kind, "\n".join(lines).strip("\n")))
            kind, lines = ("markdown" if "[markdown]" in line else "code"), []
        elif kind is not None:
            lines.append(line)
    if kind is not None:
        out.append((kind, "\n".join(lines).strip("\n")))
    return out


def _pngs(folder: Path | None) -> dict[str, float]:
    if folder is None or not folder.is_dir():
        return {}
    return {str(p.relative_to(folder)): p.stat().st_mtime_ns for p in folder.rglob("*.png")}


def main(argv: list[str]) -> None:
    script = Path(argv[0]).resolve()
    out = Path(argv[argv.index("--out") + 1]) if "--out" in argv else None
    rank0 = os.environ.get("OMPI_COMM_WORLD_RANK", "0") == "0"
    sys.argv = [str(script), *argv[1:]]
    sys.path.insert(0, str(script.parent))
    namespace = {"__name__": "__main__", "__file__": str(script)}
    for index, (kind, source) in enumerate(cells(script.read_text())):
        if kind != "code":
            continue
        before = _pngs(out)
        exec(compile(source, str(script), "exec"), namespace)
        after = _pngs(out)
        new = sorted(name for name, t in after.items() if before.get(name) != t)
        sys.stdout.flush()
        if rank0:
            print(f"{MARK} {index} {','.join(new)}@@", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
