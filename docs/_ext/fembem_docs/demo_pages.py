"""The demo gallery: a page per demos/demo_*.py with its printed tables and figures.

Each demo runs at a small size (:data:`SMALL`, the sizes the tests use) through
run_cells.py, which marks the end of every code cell's output; the page interleaves
the script's Markdown cells, its code cells, what each printed and the figures it
wrote. A run is kept in _build/demo-runs/<demo> and reused while the demo and the
sources of fem_py, bem_cpp and coupling are unchanged (a hash of them).
"""
from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from sphinx.util import logging

from . import run_cells

logger = logging.getLogger(__name__)

#: Arguments of each demo in the docs build (small sizes, as tests/test_demos.py), and
#: the number of MPI ranks (None: no mpirun).
SMALL: dict[str, tuple[list[str], int | None]] = {
    "demo_signorini_square": (["--cells", "16"], None),
    "demo_linear_transmission": (["--cells", "16"], None),
    "demo_lshape": (["--cells", "16"], None),
    "demo_jacobians": (["--cells", "16", "--repeat", "2"], None),
    "demo_mpi": (["--cells", "16"], 2),
    "demo_own_mesh": (["--cells", "16"], None),
    "demo_contact_box": (["--cells", "16"], None),
    "demo_own_body": (["--cells", "6"], None),
    "demo_shrink_fit": (["--cells", "16"], None),
    "demo_elastic_footing": (["--cells", "2"], None),
    "demo_elastic_contact": (["--cells", "32"], None),
    "demo_adaptive_lshape": (
        ["--cells", "8", "--steps", "12", "--max-dofs", "13000"],
        None,
    ),
    "demo_adaptive_lprism": (["--cells", "4", "--max-dofs", "2500"], None),
}
TIMEOUT = 600  # seconds per demo


def _sources_hash(root: Path, demo: Path, args: list[str], nprocs: int | None) -> str:
    digest = hashlib.sha256(repr((args, nprocs)).encode())
    files = [demo, root / "demos" / "common.py", Path(run_cells.__file__)]
    for package in ("fem_py", "bem_cpp", "coupling"):
        files += sorted((root / package).rglob("*.py")) + sorted((root / package).rglob("*.so"))
    for path in files:
        digest.update(str(path.relative_to(root) if path.is_relative_to(root) else path).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _run(root: Path, demo: Path, runs: Path) -> Path:
    """Run ``demo`` (or reuse its run); return the run folder (stdout.txt, out/)."""
    args, nprocs = SMALL[demo.stem]
    folder = runs / demo.stem
    key = _sources_hash(root, demo, args, nprocs)
    if (folder / "key").is_file() and (folder / "key").read_text() == key:
        return folder
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    cmd = [sys.executable, run_cells.__file__, str(demo), *args, "--out", str(folder / "out")]
    if nprocs:
        mpirun = shutil.which("mpirun")
        if mpirun is None:
            raise RuntimeError("mpirun not found: `make setup` installs openmpi-bin")
        cmd = [mpirun, "--allow-run-as-root", "--oversubscribe", "-n", str(nprocs), *cmd]
    # without the variables of an MPI job this process may be part of (a parent that
    # started MPI leaves them to its children, and mpirun then fails)
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "OPAL_"))}
    env.update(OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=root, env=env, timeout=TIMEOUT)
    if proc.returncode != 0:
        raise RuntimeError(
            f"{demo.name} {' '.join(args)} failed with exit code {proc.returncode}:\n"
            f"stdout: {proc.stdout[-2000:]}\nstderr: {proc.stderr[-3000:]}"
        )
    (folder / "stdout.txt").write_text(proc.stdout)
    (folder / "key").write_text(key)
    return folder


def _outputs(stdout: str) -> dict[int, tuple[str, list[str]]]:
    """Cell index -> (what the cell printed, the figures it wrote)."""
    found: dict[int, tuple[str, list[str]]] = {}
    text: list[str] = []
    for line in stdout.splitlines():
        m = re.fullmatch(rf"{run_cells.MARK} (\d+) (.*)@@", line)
        if m:
            figures = [f for f in m.group(2).split(",") if f]
            found[int(m.group(1))] = ("\n".join(text).strip("\n"), figures)
            text = []
        else:
            text.append(line)
    return found


_ROLE = re.compile(r":(mod|func|class|meth|data):`([^`]+)`")  # reStructuredText roles
_METHOD = re.compile(r"docs/method\.md,? sections? (\d+)")


def _markdown(source: str) -> str:
    """A Markdown cell's text: its comment marks removed, the reStructuredText roles of
    the scripts written as MyST roles, and the method's sections linked."""
    text = "\n".join(re.sub(r"^# ?", "", line) for line in source.splitlines())
    text = _ROLE.sub(r"{py:\1}`\2`", text)
    return _METHOD.sub(lambda m: f"{{ref}}`docs/method.md section {m[1]} <method-{m[1]}>`", text)


def _page(demo: Path, folder: Path, figures_dir: Path, rel_figures: str) -> tuple[str, list[str]]:
    """The page of ``demo`` and the figures it shows, in order."""
    args, nprocs = SMALL[demo.stem]
    outputs = _outputs((folder / "stdout.txt").read_text())
    out_dir = str(folder / "out")
    command = f"python demos/{demo.name} {' '.join(args)}"
    if nprocs:
        command = f"mpirun -n {nprocs} {command}"
    lines: list[str] = []
    shown: list[str] = []
    cells = run_cells.cells(demo.read_text())
    sections = _sections(demo.stem, cells)
    for index, (kind, source) in enumerate(cells):
        if kind == "markdown":
            lines += [_labelled(_markdown(source), sections), ""]
            if index == 0:  # the page's sections, then how it was made
                lines += ["```{admonition} On this page", ":class: tip", ""]
                lines += [f"- {{ref}}`{title} <{label}>`" for title, label in sections.items()]
                lines += [f"- {{ref}}`The script <{demo.stem}-source>`", "```", ""]
                lines += [
                    "```{admonition} How this page was run",
                    f"The script {{ref}}`demos/{demo.name} <{demo.stem}-source>`, run for this "
                    f"page at a small size, `{command}`: the numbers printed below are "
                    "those of that run (the text quotes the default size).",
                    "```",
                    "",
                ]
            continue
        lines += ["```python", source, "```", ""]
        printed, figures = outputs.get(index, ("", []))
        if printed:
            printed = printed.replace(out_dir, f"out/{demo.stem}")
            lines += ["```text", printed, "```", ""]
        for name in figures:
            target = figures_dir / name
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(folder / "out" / name, target)
            shown.append(name)
            lines += [f"![{name}, written by the cell above]({rel_figures}/{name})", ""]
    lines += [f"({demo.stem}-source)=", "## The script", ""]
    lines += [f"```{{literalinclude}} ../../demos/{demo.name}", ":language: python", "```", ""]
    return "\n".join(lines), shown


_SECTION = re.compile(r"^## (.+)$", re.M)


def _sections(stem: str, cells: list[tuple[str, str]]) -> dict[str, str]:
    """The titles of the page's sections (the Markdown cells' ``## `` headings, their
    inline code marks dropped) -> the label each gets (unique in the site)."""
    titles = [
        m.group(1).replace("`", "").strip()
        for kind, source in cells
        if kind == "markdown"
        for m in _SECTION.finditer(_markdown(source))
    ]
    return {title: f"{stem}-section-{k}" for k, title in enumerate(titles, start=1)}


def _labelled(text: str, sections: dict[str, str]) -> str:
    """``text`` with the label of :func:`_sections` before each ``## `` heading."""

    def label(m: re.Match) -> str:
        return f"({sections[m.group(1).replace('`', '').strip()]})=\n{m.group(0)}"

    return _SECTION.sub(label, text)


def _title(demo: Path) -> str:
    first = run_cells.cells(demo.read_text())[0][1]
    return _markdown(first).splitlines()[0].lstrip("# ").strip()


def _gallery(scripts: list[Path], figures: dict[str, list[str]]) -> list[str]:
    """A two-column table of the demos: title and the first figure each one draws."""
    cells = []
    for demo in scripts:
        cell = [f"[{_title(demo)}]({demo.stem}.md)"]
        if figures[demo.stem]:
            name = min(figures[demo.stem], key=lambda f: f != "whole_plane.png")  # else first
            cell += ["", f"[![{name}](_figures/{demo.stem}/{name})]({demo.stem}.md)"]
        cells.append(cell)
    lines = ["```{list-table}", ":widths: 50 50", ""]
    for i in range(0, len(cells), 2):
        row = cells[i : i + 2] + ([["&nbsp;"]] if i + 1 == len(cells) else [])
        for j, cell in enumerate(row):
            lines.append(("* - " if j == 0 else "  - ") + cell[0])
            lines += [("    " + text) if text else "" for text in cell[1:]]
    return lines + ["```", ""]


#: The demo shown first (``make demo`` runs it); the others follow by name.
MAIN_DEMO = "demo_signorini_square"


def demos(root: Path) -> list[Path]:
    return sorted((root / "demos").glob("demo_*.py"), key=lambda p: (p.stem != MAIN_DEMO, p.name))


def write_demo_pages(target: Path, root: Path, runs: Path) -> None:
    """Run the demos (two at a time) and write target/<demo>.md and target/index.md."""
    scripts = demos(root)
    unknown = [d.name for d in scripts if d.stem not in SMALL]
    if unknown:
        raise RuntimeError(
            f"docs/_ext/fembem_docs/demo_pages.py: give the small size of {', '.join(unknown)} "
            "in SMALL (the arguments of its docs run)"
        )
    target.mkdir(parents=True, exist_ok=True)
    with ThreadPoolExecutor(max_workers=2) as pool:
        folders = list(pool.map(lambda d: _run(root, d, runs), scripts))
    shown: dict[str, list[str]] = {}
    for demo, folder in zip(scripts, folders):
        figures = target / "_figures" / demo.stem
        shutil.rmtree(figures, ignore_errors=True)
        text, shown[demo.stem] = _page(demo, folder, figures, f"_figures/{demo.stem}")
        _write_if_changed(target / f"{demo.stem}.md", text)
    index = [
        "# Demos",
        "",
        "Commented scripts in `demos/`, written as `# %%` cells (open them as notebooks with",
        "jupytext). Each takes `--cells N` (the mesh size) and `--out DIR` (default",
        "`out/<demo name>`), prints its tables on rank 0 and writes the numbers to",
        "`DIR/results.json`; the test suite runs each at a small size and checks those",
        "numbers. The pages below show each script with what it printed and drew when",
        "run at a small size for this site.",
        "",
        "",
        *_gallery(scripts, shown),
        "```{toctree}",
        ":hidden:",
        "",
        *[d.stem for d in scripts],
        "```",
        "",
    ]
    _write_if_changed(target / "index.md", "\n".join(index))


def _write_if_changed(path: Path, text: str) -> None:
    if not path.is_file() or path.read_text() != text:
        path.write_text(text)
