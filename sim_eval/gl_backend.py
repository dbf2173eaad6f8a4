"""MuJoCo's OpenGL backend (``MUJOCO_GL``) checked before a command needs MuJoCo.

A ``MUJOCO_GL`` that names an unknown backend or one whose library is missing (OSMesa) breaks
``import mujoco`` itself, wherever a command first imports it, with a traceback. This module
imports MuJoCo only inside :func:`check_mujoco_gl`, so that the failure becomes one line.
"""

from __future__ import annotations

import os

from ogcp.planner.infra.errors import OgcpError


def check_mujoco_gl() -> None:
    """Refuse a set ``MUJOCO_GL`` that MuJoCo cannot load (nothing is imported when it is unset).

    Raises:
        OgcpError: One line naming the backend, the import's error and the remedies.
    """
    backend = os.environ.get("MUJOCO_GL")
    if not backend:
        return
    try:
        import mujoco  # noqa: F401
    except Exception as exc:
        raise OgcpError(
            f"MUJOCO_GL={backend}: MuJoCo cannot load this OpenGL backend here ({type(exc).__name__}: {exc}); "
            "install its library (OSMesa: Debian's libosmesa6; EGL: libegl1), choose egl, osmesa or glfw, "
            "or unset MUJOCO_GL"
        ) from exc
