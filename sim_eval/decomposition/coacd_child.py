"""CoACD in a child process: killable past a timeout, and a native crash cannot take the caller down.

The child runs :func:`_child_main` from its source with ``python -c``: importing ``sim_eval``
would load the whole package (MuJoCo included) just to call CoACD. Arrays travel through
``.npz`` files in a temporary folder; CoACD's log goes to a file the parent reads.

The child ends with its parent, even one killed by SIGKILL (:mod:`ogcp.planner.infra.lifetime`:
``PR_SET_PDEATHSIG`` on Linux, where the starting thread waits for the child, and a watchdog
thread everywhere), and the folder of a killed run is removed by a later one.
"""

from __future__ import annotations

import inspect
import json
import os
import subprocess
import sys
import time
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from ogcp.planner.infra.errors import OgcpError
from ogcp.planner.infra.lifetime import owned_tempdir, set_parent_death_signal, watch_parent

_POLL_S = 0.2  # [s] how often the parent checks on the child
#: Prefix of the temporary folders; a folder is ``<prefix><owner pid>-<random>``.
TEMP_PREFIX = "ogcp-coacd-"


def _child_command(workdir: Path) -> list[str]:
    # The child runs this module's _child_main from source: importing sim_eval would load the
    # whole package (MuJoCo included) just to call CoACD. The lifetime guards travel with it.
    functions = (set_parent_death_signal, watch_parent, _child_main)
    source = "\n\n".join(inspect.getsource(function) for function in functions)
    source += "\nimport sys\nsys.exit(_child_main(sys.argv[1], int(sys.argv[2])))\n"
    return [sys.executable, "-c", source, str(workdir), str(os.getpid())]


def _wait(proc: subprocess.Popen[bytes], timeout: float, name: str, progress: bool) -> None:
    start = time.monotonic()
    with tqdm(
        desc=f"CoACD {name}", bar_format="{desc}: {elapsed} elapsed", file=sys.stderr, disable=not progress
    ) as bar:
        try:
            while True:
                remaining = timeout - (time.monotonic() - start)
                if remaining <= 0:
                    raise OgcpError(
                        f"CoACD did not finish within {timeout:g} s on {name}; raise --timeout or increase threshold"
                    )
                try:
                    proc.wait(timeout=min(_POLL_S, remaining))
                    return
                except subprocess.TimeoutExpired:
                    bar.refresh()
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()


def run_coacd_child(
    vertices: NDArray[np.float64],
    faces: NDArray[np.int64],
    kwargs: dict[str, Any],
    timeout: float,
    name: str,
    progress: bool,
) -> tuple[list[NDArray[np.float64]], float, str]:
    """Run ``coacd.run_coacd(mesh, **kwargs)`` in a child process.

    Args:
        vertices: Mesh vertices, shape (v, 3) [m].
        faces: Mesh faces, shape (f, 3).
        kwargs: CoACD keyword arguments.
        timeout: Wall-clock limit [s]; the child is killed past it.
        name: Object name for messages.
        progress: Show an elapsed-time indicator on stderr.

    Returns:
        Part vertex sets, CoACD's own wall time [s] and its log.

    Raises:
        OgcpError: Timeout, a Python error in CoACD, a native crash or an unreadable result.
    """
    with owned_tempdir(TEMP_PREFIX) as workdir:
        np.savez(workdir / "input.npz", vertices=vertices, faces=faces.astype(np.int32))
        (workdir / "job.json").write_text(json.dumps(kwargs))
        with open(workdir / "coacd.log", "wb") as log:
            proc = subprocess.Popen(
                _child_command(workdir), stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL
            )
            _wait(proc, timeout, name, progress)
        text = (workdir / "coacd.log").read_text(errors="replace")
        if proc.returncode != 0:
            error = workdir / "error.txt"
            if error.is_file():
                raise OgcpError(f"CoACD failed on {name}: {error.read_text().strip()}")
            how = f"signal {-proc.returncode}" if proc.returncode < 0 else f"exit status {proc.returncode}"
            last = next((line.strip() for line in reversed(text.splitlines()) if line.strip()), "no output")
            raise OgcpError(f"CoACD crashed on {name} ({how}): {last}")
        try:
            with np.load(workdir / "parts.npz", allow_pickle=False) as data:
                parts = [np.asarray(data[f"arr_{i}"], dtype=np.float64) for i in range(len(data.files))]
            seconds = float(json.loads((workdir / "result.json").read_text())["seconds"])
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
            raise OgcpError(f"CoACD left no readable result on {name}: {exc}") from exc
    return parts, seconds, text


def _child_main(workdir: str, parent_pid: int) -> int:
    """Child process: CoACD on ``input.npz`` with ``job.json``; writes ``parts.npz``, ``result.json``.

    Runs from its own source (see :func:`_child_command`), so it imports what it uses itself
    and uses no module globals but the lifetime guards sent along with it. It ends with
    ``parent_pid``: nobody would read its result.
    """
    set_parent_death_signal()  # Linux: the parent thread that started us waits for us
    watch_parent(parent_pid)  # elsewhere, and if the parent died before the line above

    import json
    import os
    import time

    import numpy as np

    try:
        import coacd

        with open(os.path.join(workdir, "job.json")) as handle:
            kwargs = json.load(handle)
        with np.load(os.path.join(workdir, "input.npz")) as data:
            mesh = coacd.Mesh(data["vertices"], data["faces"])
        coacd.set_log_level("info")  # to the log file, where the parent reads the remeshing decision
        start = time.perf_counter()
        result = coacd.run_coacd(mesh, **kwargs)
        seconds = time.perf_counter() - start
        if not result:
            raise RuntimeError("CoACD returned no parts")
        np.savez(os.path.join(workdir, "parts.npz"), *[np.asarray(v, dtype=np.float64) for v, _ in result])
        with open(os.path.join(workdir, "result.json"), "w") as handle:
            json.dump({"seconds": seconds}, handle)
    except Exception as exc:  # noqa: BLE001 - every failure must reach the parent as a message
        with open(os.path.join(workdir, "error.txt"), "w") as handle:
            handle.write(f"{type(exc).__name__}: {exc}".strip().splitlines()[0] + "\n")
        return 1
    return 0
