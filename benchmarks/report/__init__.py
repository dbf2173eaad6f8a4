"""Self-contained HTML: the report of a suite run (``ogcp report``) and the 3D view of one result (``ogcp view``).

The pages open offline: the viewer (:mod:`ogcp.benchmarks.report.viewer`, plain JavaScript on a
2D canvas), the scene data and the figures are all inside the one file.
"""

from ogcp.benchmarks.report.html import REPORT_NAME, ReportResult, write_report, write_view

__all__ = ["REPORT_NAME", "ReportResult", "write_report", "write_view"]
