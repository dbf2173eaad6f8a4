"""No process of ogcp outlives its parent: killed suites, killed decompositions, stale folders.

Each test starts the parent in its own session, records the process tree from ``/proc`` (pid
and start time, so a reused pid is not mistaken for a survivor), kills the parent and expects
every descendant gone within :data:`GRACE_S`. Whatever is left is killed at teardown.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import signal
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from ogcp.planner.infra.lifetime import owned_tempdir, remove_stale_tempdirs

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the process tree from /proc")

GRACE_S = 10.0  # [s] the most a process of ogcp may outlive its parent
START_S = 90.0  # [s] time allowed for the workers to appear on a loaded machine
ROOT = Path(__file__).resolve().parents[2]
TICK = os.sysconf("SC_CLK_TCK")
SLOW_SUITE = """
schema_version = 1
name = "orphans"
objects = ["box", "donut"]
contacts = 300
m = [3]
simulate = false

[[methods]]
method = "hfts"
runs = 40
iterations = 200
label = "HFTS"
"""


def _stat(pid: int) -> tuple[str, int, int, float] | None:
    """State, parent pid, start time [ticks] and CPU time [s] of a process, None when gone."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2 :].split()  # the name in parentheses may hold spaces
    return fields[0], int(fields[1]), int(fields[19]), (int(fields[11]) + int(fields[12])) / TICK


def _descendants(root: int) -> dict[int, int]:
    """Every living descendant of ``root``: pid -> start time."""
    table = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit() and (stat := _stat(int(entry.name))) is not None and stat[0] not in "ZX":
            table[int(entry.name)] = stat
    found: dict[int, int] = {}
    frontier = [root]
    while frontier:
        parent = frontier.pop()
        for pid, (_, ppid, start, _) in table.items():
            if ppid == parent and pid not in found:
                found[pid] = start
                frontier.append(pid)
    return found


def _alive(pid: int, start: int) -> bool:
    stat = _stat(pid)
    return stat is not None and stat[2] == start and stat[0] not in "ZX"  # a zombie holds nothing


def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


class Parents:
    """The parents a test starts and the trees it records; whatever is left is killed at teardown."""

    def __init__(self, tmp_path: Path) -> None:
        self.tmp_path = tmp_path
        self.started: list[subprocess.Popen[bytes]] = []
        self.trees: dict[int, int] = {}

    def spawn(self, argv: list[str]) -> subprocess.Popen[bytes]:
        env = {**os.environ, "OGCP_CACHE": str(self.tmp_path / "cache"), "TMPDIR": str(self.tmp_path)}
        with open(self.tmp_path / "parent.log", "wb") as log:
            proc = subprocess.Popen(
                argv,
                cwd=ROOT,
                env=env,
                stdout=log,
                stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL,
                start_new_session=True,
            )
        self.started.append(proc)
        return proc

    def wait_for(self, proc: subprocess.Popen[bytes], condition: Callable[[], bool], what: str) -> None:
        """Poll ``condition`` until it holds; fail with the parent's log if it exits or START_S passes."""
        deadline = time.monotonic() + START_S
        while not condition():
            if proc.poll() is not None or time.monotonic() > deadline:
                log = (self.tmp_path / "parent.log").read_text(errors="replace")[-2000:]
                pytest.fail(f"no {what} (parent exit status {proc.poll()}); its log:\n{log}")
            time.sleep(0.2)

    def survivors_after_kill(self, proc: subprocess.Popen[bytes], sig: signal.Signals) -> dict[int, str]:
        """Kill ``proc`` with ``sig``; its descendants still alive after GRACE_S, with their command."""
        tree = _descendants(proc.pid)
        assert tree, "the parent has no child processes to check"
        self.trees.update(tree)
        proc.send_signal(sig)
        proc.wait(timeout=GRACE_S)
        deadline = time.monotonic() + GRACE_S
        while time.monotonic() < deadline and any(_alive(pid, start) for pid, start in tree.items()):
            time.sleep(0.2)
        return {pid: _cmdline(pid) for pid, start in tree.items() if _alive(pid, start)}

    def clean_up(self) -> None:
        for proc in self.started:
            if proc.poll() is None:
                self.trees.update(_descendants(proc.pid))
                proc.kill()
                proc.wait()
        for pid, start in self.trees.items():
            if _alive(pid, start):
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)


@pytest.fixture
def parents(tmp_path: Path) -> Iterator[Parents]:
    """Start parents; on teardown they and the trees recorded from them are killed."""
    started = Parents(tmp_path)
    yield started
    started.clean_up()


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["sigterm", "sigkill"])
def test_a_killed_suite_leaves_no_worker(tmp_path: Path, parents: Parents, sig: signal.Signals) -> None:
    suite = tmp_path / "slow.toml"
    suite.write_text(SLOW_SUITE)
    argv = [
        sys.executable,
        "-m",
        "ogcp.benchmarks.cli",
        "suite",
        str(suite),
        "--jobs",
        "2",
        "--out",
        str(tmp_path / "out"),
    ]
    proc = parents.spawn(argv)

    def started_workers() -> bool:
        # Both loky workers past their start (their cell is on its way to them).
        workers = [pid for pid in _descendants(proc.pid) if "LokyProcess" in _cmdline(pid)]
        return len(workers) >= 2 and all((_stat(pid) or ("", 0, 0, 0.0))[3] > 0.5 for pid in workers)

    parents.wait_for(proc, started_workers, "two started loky workers")
    assert parents.survivors_after_kill(proc, sig) == {}


def _threads(pid: int) -> int:
    """Threads of a live process (0 once it is gone)."""
    try:
        return len(os.listdir(f"/proc/{pid}/task"))
    except OSError:
        return 0


NAPS = """
import sys, time
from pathlib import Path

import ogcp.planner.infra.parallel as parallel

if sys.argv[1] == "tasks-only":  # the guard a task starts, alone (joblib < 1.5)
    parallel._has_initializer = lambda version: False


def nap(marker):
    Path(marker).touch()
    time.sleep(120)


list(parallel.run_tasks(nap, [(marker,) for marker in sys.argv[2:]], jobs=2))
"""


@pytest.mark.parametrize(
    "guard, tasks",
    [("initializer", 1), ("tasks-only", 2)],
    ids=["a-worker-without-a-task", "guarded-by-the-tasks"],
)
def test_killed_run_tasks_leaves_no_worker(tmp_path: Path, parents: Parents, guard: str, tasks: int) -> None:
    # With one task for two workers, the second idles: only the worker initializer guards it.
    markers = [tmp_path / f"task{i}" for i in range(tasks)]
    proc = parents.spawn([sys.executable, "-c", NAPS, guard, *map(str, markers)])

    def running() -> bool:
        # Each worker past its start-up: its guard thread runs beside its main thread. (A parent
        # killed while a worker is still starting is not covered: loky's start-up reads from the
        # parent before any code of ogcp runs in the worker.)
        workers = [pid for pid in _descendants(proc.pid) if "LokyProcess" in _cmdline(pid)]
        guarded = all(_threads(pid) >= 2 for pid in workers)
        return len(workers) >= 2 and guarded and all(marker.exists() for marker in markers)

    parents.wait_for(proc, running, "running tasks")
    assert parents.survivors_after_kill(proc, signal.SIGKILL) == {}


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["sigterm", "sigkill"])
def test_a_killed_decomposition_leaves_no_coacd_child(tmp_path: Path, parents: Parents, sig: signal.Signals) -> None:
    # A ring fine enough that CoACD runs for seconds; the parent is killed once the child runs.
    script = textwrap.dedent(
        """
        import trimesh
        from ogcp.sim_eval.decomposition.coacd_child import run_coacd_child

        mesh = trimesh.creation.annulus(r_min=0.05, r_max=0.1, height=0.05, sections=64)
        run_coacd_child(mesh.vertices, mesh.faces, {"threshold": 0.01}, 300.0, "ring", False)
        """
    )
    proc = parents.spawn([sys.executable, "-c", script])

    def coacd_child() -> bool:
        return any("_child_main" in _cmdline(pid) for pid in _descendants(proc.pid))

    parents.wait_for(proc, coacd_child, "CoACD child")
    assert parents.survivors_after_kill(proc, sig) == {}
    left = [path.name for path in tmp_path.glob("ogcp-coacd-*")]
    assert left and all(name.startswith(f"ogcp-coacd-{proc.pid}-") for name in left)
    assert remove_stale_tempdirs("ogcp-coacd-", root=tmp_path, min_age_s=0) == [tmp_path / name for name in left]
    assert not list(tmp_path.glob("ogcp-coacd-*"))


GUARDED_CHILD = """
import os, sys, time
from pathlib import Path
from ogcp.planner.infra import lifetime

if sys.argv[1] == "watchdog":
    lifetime.watch_parent(os.getppid())
else:
    assert lifetime.set_parent_death_signal()
Path(sys.argv[2]).touch()
time.sleep(120)
"""


@pytest.mark.parametrize("guard", ["watchdog", "death-signal"])
def test_each_guard_alone_ends_a_child_whose_parent_dies(tmp_path: Path, parents: Parents, guard: str) -> None:
    # The watchdog is the guard on macOS; the death signal acts even inside native code.
    marker = tmp_path / "guarded"
    child = [sys.executable, "-c", GUARDED_CHILD, guard, str(marker)]
    script = f"import subprocess, time; subprocess.Popen({child!r}); time.sleep(120)"
    proc = parents.spawn([sys.executable, "-c", script])
    parents.wait_for(proc, marker.exists, "guarded child")
    assert parents.survivors_after_kill(proc, signal.SIGKILL) == {}


def _dead_pid() -> int:
    done = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, check=True)
    return int(done.stdout)


def test_only_the_folders_of_dead_owners_are_removed(tmp_path: Path) -> None:
    dead = _dead_pid()
    old = time.time() - 3600
    folders = {
        "stale": tmp_path / f"ogcp-coacd-{dead}-stale",
        "live owner": tmp_path / f"ogcp-coacd-{os.getpid()}-live",
        "locked": tmp_path / f"ogcp-coacd-{dead}-locked",
        "young": tmp_path / f"ogcp-coacd-{dead}-young",
        "other prefix": tmp_path / f"ogcp-other-{dead}-x",
    }
    for folder in folders.values():
        folder.mkdir()
        (folder / "input.npz").write_bytes(b"x")
        (folder / ".owner.lock").touch()
    for name, folder in folders.items():
        if name != "young":
            os.utime(folder, (old, old))
    with open(folders["locked"] / ".owner.lock", "rb") as held:  # an owner in another pid namespace
        fcntl.flock(held.fileno(), fcntl.LOCK_EX)
        assert remove_stale_tempdirs("ogcp-coacd-", root=tmp_path) == [folders["stale"]]
    assert sorted(path.name for path in tmp_path.iterdir()) == sorted(
        folder.name for name, folder in folders.items() if name != "stale"
    )


def test_an_owned_folder_is_named_locked_and_removed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    stale = tmp_path / f"ogcp-coacd-{_dead_pid()}-stale"
    stale.mkdir()
    os.utime(stale, (time.time() - 3600,) * 2)
    with owned_tempdir("ogcp-coacd-") as folder:
        assert not stale.exists()
        assert folder.parent == tmp_path and folder.name.startswith(f"ogcp-coacd-{os.getpid()}-")
        with open(folder / ".owner.lock", "rb") as probe, pytest.raises(BlockingIOError):
            fcntl.flock(probe.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        assert remove_stale_tempdirs("ogcp-coacd-", min_age_s=0) == []
    assert not folder.exists()
