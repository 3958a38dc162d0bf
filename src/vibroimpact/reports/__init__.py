"""What the report notebooks call: the paper's findings measured on a run's datasets
(:mod:`.findings`) and the small helpers that show figures and tables (:mod:`.notebook`).

No numerics live in the notebooks; nothing here loads numba.
"""
