"""Which hands ogcp knows by name, and how ``--hand`` resolves a name or a descriptor path."""

from __future__ import annotations

from pathlib import Path

from ogcp.planner.config.methods import HANDS
from ogcp.planner.hands.descriptor import HandDescriptor, load_descriptor
from ogcp.planner.infra.assets import asset_path
from ogcp.planner.infra.errors import OgcpError

#: Built-in hands: name -> descriptor shipped in ``assets/hands/``.
BUILTIN_HANDS = {name: f"hands/{name}.toml" for name in HANDS}
DESCRIPTOR_SUFFIX = ".toml"


def is_descriptor_path(hand: str | Path) -> bool:
    """Whether ``--hand`` names a file rather than a built-in hand."""
    text = str(hand)
    return isinstance(hand, Path) or text.endswith(DESCRIPTOR_SUFFIX) or "/" in text or "\\" in text


def resolve_hand(hand: str | Path, relative_to: Path | None = None) -> HandDescriptor:
    """The descriptor of a built-in hand name or of an ``ogcp.hand/1`` file.

    Args:
        hand: A name in :data:`BUILTIN_HANDS`, or a path to a ``.toml`` descriptor.
        relative_to: Folder a relative descriptor path is taken from (a suite's folder); None:
            the working directory.

    Raises:
        OgcpError: For an unknown name (listing the built-ins) or a bad descriptor.
    """
    if is_descriptor_path(hand):
        path = Path(hand).expanduser()
        if relative_to is not None and not path.is_absolute():
            path = relative_to / path
        return load_descriptor(path)
    name = str(hand)
    if name not in BUILTIN_HANDS:
        raise OgcpError(
            f"unknown hand {name!r}; built-in hands are {', '.join(sorted(BUILTIN_HANDS))}, or give an "
            f"ogcp.hand/1 descriptor file (*.toml)"
        )
    return load_descriptor(asset_path(BUILTIN_HANDS[name]))
