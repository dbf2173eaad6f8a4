"""Versioned JSON records that planner writes and later stages read (``ogcp.plan/1``)."""
