"""imageform.report: figures and the self-contained simulation report (report.html)."""

from imageform.report.html import ReportPaths, write_report

__all__ = ["ReportPaths", "write_report"]
