"""From the report's cells to our rows: which structure setting stands for which report column."""
