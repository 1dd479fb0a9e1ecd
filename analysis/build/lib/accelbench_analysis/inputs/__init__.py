"""What is read: the harness CSVs and their contract (schema), the report's numbers."""
