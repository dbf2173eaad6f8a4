"""Baselines that ogcp's search is compared with: exhaustive search (ES)."""
