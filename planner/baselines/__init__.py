"""Baselines that ogcp's search is compared with: exhaustive search (ES) and HFTS."""

from ogcp.planner.baselines.es import ES_METHODS, ESResult, ExhaustiveSearch
from ogcp.planner.baselines.hfts import HFTS, HFTSResult, HFTSRun
from ogcp.planner.config.methods import DEFAULT_BINS, DEFAULT_CHUNK

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
