"""sirl_bench: read sirl-bench results files as typed pandas DataFrames.

    import sirl_bench
    r = sirl_bench.open("out/quick.h5")
    r.tables["tpa"]     # or r.tpa: one row per TPA cell, typed
    r.curves            # learning curves, long format
    r.provenance        # engine version, commit, CPU class, profile text, ...
"""
from .results import (FLAG_COLUMNS, SCHEMA_VERSIONS, Results, ResultsError, claims,  # noqa: F401
                      datasets, open, study_analysis, typed)

__all__ = ["FLAG_COLUMNS", "SCHEMA_VERSIONS", "Results", "ResultsError", "claims", "datasets",
           "open", "study_analysis", "typed"]
__version__ = "0.8.0"
