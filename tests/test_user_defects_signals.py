"""Issue 29, item 4: a run killed where it cannot clean up (SIGKILL) leaves its staging
folder; the next run into the same place removes it, and keeps a live run's."""
from __future__ import annotations

import fcntl
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import ROOT, run_cli
from coupling.io.atomic import remove_stale_staging

FEMBEM = str(Path(sys.executable).parent / "fembem")
CONFIG = """\
[geometry]
h = {h}
subdomain_size = {d}
signorini = ["bottom"]
[solver]
method = "pgpm"
"""


def _signalled(command: list[str], prefix: str, signum: int) -> subprocess.Popen:
    """Start ``command`` and send it ``signum`` once it prints a line starting with
    ``prefix`` (its stderr kept for the caller)."""
    proc = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT
    )
    for line in proc.stdout:
        if line.startswith(prefix):
            proc.send_signal(signum)
            break
    return proc


def _killed_run(tmp_path: Path, out: Path) -> None:
    """Start a long run into ``out`` and SIGKILL it once it solves."""
    config = tmp_path / "long.toml"
    config.write_text(CONFIG.format(h=1 / 512, d=1 / 128))
    proc = _signalled([FEMBEM, "solve", str(config), "--out", str(out)], "  it ", signal.SIGKILL)
    proc.wait(timeout=60)
    assert proc.returncode == -signal.SIGKILL


def test_the_next_run_removes_the_staging_folder_of_a_killed_run(tmp_path):
    out = tmp_path / "out"
    _killed_run(tmp_path, out)
    stale = list(tmp_path.glob(".out.partial-*"))
    assert len(stale) == 1  # nothing could remove it
    config = tmp_path / "c.toml"
    config.write_text(CONFIG.format(h=1 / 16, d=1 / 4))
    proc = run_cli("solve", str(config), "--out", str(out), "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert not list(tmp_path.glob(".out.*"))
    assert (out / "summary.json").is_file() and not (out / ".lock").exists()


def test_a_live_runs_staging_folder_is_kept(tmp_path):
    out = tmp_path / "out"
    live, dead, unlocked = (tmp_path / f".out.partial-{k}" for k in ("live", "dead", "new"))
    for folder in (live, dead, unlocked):
        folder.mkdir()
    (dead / ".lock").touch()
    fd = os.open(live / ".lock", os.O_CREAT | os.O_RDWR)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        # flock locks belong to the open file: another process sees this one as locked
        script = (
            "import sys; from pathlib import Path; from coupling.io.atomic import "
            "remove_stale_staging; print([p.name for p in remove_stale_staging(Path(sys.argv[1]))])"
        )
        proc = subprocess.run(
            [sys.executable, "-c", script, str(out)], capture_output=True, text=True, cwd=ROOT
        )
        assert proc.stdout.strip() == "['.out.partial-dead']", proc.stderr
    finally:
        os.close(fd)
    assert live.is_dir() and unlocked.is_dir() and not dead.exists()
    assert remove_stale_staging(out) == [live]  # its run has ended now


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_run_stuck_in_native_code_ends_on_a_signal(tmp_path, signum):
    config = tmp_path / "c.toml"
    config.write_text(CONFIG.format(h=1 / 16, d=1 / 4))
    out = tmp_path / "out"
    script = str(ROOT / "tests" / "mpi" / "stuck_in_native_code.py")
    proc = _signalled(
        [sys.executable, script, "solve", str(config), "--out", str(out)], "stuck", signum
    )
    # before issue 29 it never ended; the helper ends it WATCHDOG_GRACE_SECONDS after
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode in (-signum, 128 + signum), stderr  # by the signal, as a shell sees
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert lines == [f"fembem: interrupted by {signum.name}; no output of this run was kept"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.toml"]  # no staging folder left


# Issue 66, item 2: gmsh's Python module sets SIGINT to the default action on import, so a
# Ctrl-C while gmsh meshed killed the run with no message and left its staging folder.

BALL = '[geometry]\nshape = "ball"\nradius = 0.25\nh = 0.008\nsignorini = ["bottom"]\n'


def test_a_gmsh_session_keeps_the_sigint_action():
    from fem_py.mesh.gmsh_mesh import gmsh_session
    from fem_py.signals import sigaction

    def handler(signum, frame):
        pass

    previous = signal.signal(signal.SIGINT, handler)
    try:
        action = sigaction(signal.SIGINT)
        action.flags |= 0x80000000  # SA_RESETHAND, as the watchdog sets it
        sigaction(signal.SIGINT, action)
        for _ in range(2):  # gmsh's import (once per process) and its finalize
            with gmsh_session() as gmsh:
                assert signal.getsignal(signal.SIGINT) is handler
                gmsh.model.add("empty")
            assert signal.getsignal(signal.SIGINT) is handler
            kept = sigaction(signal.SIGINT)
            assert (kept.handler, kept.flags) == (action.handler, action.flags)
    finally:
        signal.signal(signal.SIGINT, previous)


def test_ctrl_c_while_gmsh_meshes_ends_in_one_line(tmp_path):
    import time

    config = tmp_path / "ball.toml"
    config.write_text(BALL)  # gmsh meshes it for 15-25 s
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [FEMBEM, "solve", str(config), "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    )
    for line in proc.stdout:
        if line.startswith("fembem: building the mesh"):
            time.sleep(2.0)  # gmsh is meshing now
            proc.send_signal(signal.SIGINT)
            break
    stdout, stderr = proc.communicate(timeout=60)
    # gmsh does not return to Python while it meshes: the watchdog ends the run by the
    # signal 3 s later (exit status 130 as a shell sees it), after its one line
    assert proc.returncode in (-signal.SIGINT, 130), stderr
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert lines == ["fembem: interrupted by SIGINT; no output of this run was kept"]
    assert "  it " not in stdout, "the signal came after the mesh"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ball.toml"]
