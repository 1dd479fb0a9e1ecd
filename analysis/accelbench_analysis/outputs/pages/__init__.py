"""The HTML pages: a run's page, the list of runs, the history page, and what they share."""
