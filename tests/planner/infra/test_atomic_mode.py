"""Atomically written files are readable by whoever a plain ``open(path, "w")`` would let read them.

The temporary file is created with mode 0666 and the kernel applies the umask (0644 under the usual
umask 022), as for a plain open: never the 0600 of ``tempfile.mkstemp``. Each case runs in a child
process, because the umask is process-wide and changing it here would race other threads.
"""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]

CHILD = """
import json, os, stat, sys
from pathlib import Path
from ogcp.planner.infra import write_atomic, write_bytes_atomic, write_json_atomic, write_text_atomic

os.umask(int(sys.argv[2], 8))
folder = Path(sys.argv[1])
(folder / "plain").write_bytes(b"x")
write_bytes_atomic(folder / "bytes", b"x")
write_text_atomic(folder / "text", "x")
write_json_atomic(folder / "deep" / "new" / "json", [1])
write_atomic(folder / "handle", lambda handle: handle.write(b"x"))
replaced = folder / "replaced"
replaced.write_bytes(b"old")
os.chmod(replaced, 0o600)
write_bytes_atomic(replaced, b"new")
modes = {p.name: stat.S_IMODE(p.stat().st_mode) for p in folder.rglob("*") if p.is_file()}
print(json.dumps(modes))
"""


def _modes_under(umask: int, folder: Path) -> dict[str, int]:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    done = subprocess.run(
        [sys.executable, "-c", CHILD, str(folder), f"{umask:o}"], capture_output=True, text=True, env=env, check=True
    )
    return json.loads(done.stdout)


@pytest.mark.skipif(os.name != "posix", reason="file modes and the umask are POSIX")
@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_atomic_files_get_the_mode_of_a_plain_open(tmp_path: Path, umask: int) -> None:
    modes = _modes_under(umask, tmp_path)
    expected = 0o666 & ~umask
    assert modes["plain"] == expected
    # Every writer, a new folder, and a target that existed with 0600 (it is replaced, not rewritten).
    assert modes == dict.fromkeys(["plain", "bytes", "text", "json", "handle", "replaced"], expected)


@pytest.mark.skipif(os.name != "posix", reason="file modes and the umask are POSIX")
def test_under_the_usual_umask_colleagues_can_read_the_results(tmp_path: Path) -> None:
    modes = _modes_under(0o022, tmp_path)
    assert all(mode == 0o644 and mode & stat.S_IROTH for mode in modes.values())
