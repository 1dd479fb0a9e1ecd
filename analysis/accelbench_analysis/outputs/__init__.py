"""What is written: tables, claims, figures, the comparison, REPORT.md, robustness, scaling, regressions."""
