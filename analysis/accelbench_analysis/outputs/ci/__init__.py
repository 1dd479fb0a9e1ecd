"""The CI side: the regression check against the committed baseline and the history across commits."""
