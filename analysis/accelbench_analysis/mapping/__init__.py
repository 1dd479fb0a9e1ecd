"""What every output shares: from the report's cells to our rows (selection), the metrics
and ratios, the formatting of numbers and tables, the error columns, the styles."""
