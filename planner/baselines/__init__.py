"""Baselines that ogcp's search is compared with: exhaustive search (ES) and HFTS."""

from planner.baselines.es import DEFAULT_BINS, DEFAULT_CHUNK, ES_METHODS, ESResult, ExhaustiveSearch
from planner.baselines.hfts import HFTS, HFTSResult, HFTSRun

__all__ = [
    "DEFAULT_BINS",
    "DEFAULT_CHUNK",
    "ES_METHODS",
    "HFTS",
    "ESResult",
    "ExhaustiveSearch",
    "HFTSResult",
    "HFTSRun",
]
