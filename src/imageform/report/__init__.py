"""imageform.report: figures and the self-contained simulation report (report.html)."""

from imageform.report.chromaticity_plot import plot_chromaticity_diagram
from imageform.report.html import ReportPaths, write_report
from imageform.report.overlays import draw_pose_overlay

__all__ = ["ReportPaths", "draw_pose_overlay", "plot_chromaticity_diagram", "write_report"]
