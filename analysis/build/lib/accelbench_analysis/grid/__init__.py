"""Parameter grid search: grid configs and the ranking of their candidates."""
