"""The validation report: one self-contained HTML file with embedded figures.

matplotlib is imported inside the figure functions (Agg backend), not at ``import fivid.report``'s
callers' import time.
"""

from fivid.report.build import amplitude_interval, measured_peaks, render_report

__all__ = ["render_report", "measured_peaks", "amplitude_interval"]
