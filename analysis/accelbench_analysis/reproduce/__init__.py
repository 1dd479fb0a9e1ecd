"""The main job: measure configs into a run directory of their own (job.py), its bookkeeping (runs.py)."""
