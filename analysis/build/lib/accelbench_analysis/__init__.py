"""accelbench analysis: the harness's CSV -> the report's tables, claims, figures and REPORT.md."""

__version__ = "0.1.0"
