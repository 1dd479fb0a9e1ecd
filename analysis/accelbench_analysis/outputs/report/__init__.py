"""REPORT.md and what it is made of: Tables 2, 4, 5, the claims, the three-way comparison, the cost model, robustness."""
