"""What is written, by role: figures/, report/ (REPORT.md's tables, claims, comparison),
ci/ (the regression check, the history across commits) and pages/ (the HTML pages)."""
