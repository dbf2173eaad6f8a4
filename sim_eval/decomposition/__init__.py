"""Convex decomposition of object meshes for MuJoCo: CoACD in a child process, cached by content."""

from sim_eval.decomposition.decompose import CacheWriteWarning, Decomposition, cache_key, coacd_version, decompose
from sim_eval.decomposition.settings import DecompositionSettings

__all__ = ["CacheWriteWarning", "Decomposition", "DecompositionSettings", "cache_key", "coacd_version", "decompose"]
