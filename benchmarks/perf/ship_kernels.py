"""Rebuild the compiled kernels that ship with ogcp (:mod:`ogcp.planner.grasp.kernel.shipped`).

Run after editing a kernel's source (``tests/planner/grasp/test_shipped_kernels.py`` says when the
shipped files are stale): ``python -m ogcp.benchmarks.perf.ship_kernels``. It compiles every kernel
family for the x86-64-v3 level in a child process (about 40 s on two cores) and replaces this
Python's files in ``planner/grasp/kernel/shipped/``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from ogcp.planner.grasp.kernel.jit import restamp_index
from ogcp.planner.grasp.kernel.shipped import SHIPPED, SHIPPED_CPU, shipped_stamp, source_digest


def build(destination: Path = SHIPPED) -> int:
    """Compile every kernel family for :data:`~ogcp.planner.grasp.kernel.shipped.SHIPPED_CPU` and keep the cache files in ``destination``.

    The kernels compile in a child process (``NUMBA_CPU_NAME`` that level, an empty numba cache),
    through the same warm-up the planners use; each index is then stamped with
    :func:`~ogcp.planner.grasp.kernel.shipped.source_digest`. Files of this Python that ``destination`` held before are replaced.

    Returns:
        The number of files written.
    """
    with tempfile.TemporaryDirectory(prefix="ogcp-shipped-") as folder:
        env = {
            **os.environ,
            "NUMBA_CPU_NAME": SHIPPED_CPU,
            "NUMBA_CPU_FEATURES": "",
            "NUMBA_CACHE_DIR": folder,
            "OGCP_SHIPPED_KERNELS": "0",
        }
        code = "from ogcp.planner.methods.warm_up import warm_up; warm_up(parallel=False)"
        subprocess.run([sys.executable, "-c", code], check=True, env=env)
        tag = f".py{sys.version_info.major}{sys.version_info.minor}."
        files = sorted(p for p in Path(folder).rglob("*.ogcp*.nb[ic]") if tag in p.name)
        names = [p.name for p in files]
        if len(set(names)) != len(names):
            raise RuntimeError("two kernels' cache files share a name; shipped files are kept flat")
        destination.mkdir(parents=True, exist_ok=True)
        for old in destination.glob(f"*{tag}*"):
            old.unlink()
        for path in files:
            target = destination / path.name
            if path.suffix == ".nbi":
                restamp_index(path, target, shipped_stamp())
            else:
                shutil.copyfile(path, target)
    return len(files)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    parser.add_argument("--out", type=Path, default=SHIPPED, help=f"destination folder (default {SHIPPED})")
    args = parser.parse_args(argv)
    count = build(args.out)
    print(f"wrote {count} files to {args.out} (sources {source_digest()[:12]})")


if __name__ == "__main__":
    main()
