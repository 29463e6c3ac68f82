"""sirl_bench: read sirl-bench results files as typed pandas DataFrames, and write the embeddings
file `sirl evaluate` scores.

    import sirl_bench
    r = sirl_bench.open("out/quick.h5")
    r.tables["tpa"]     # or r.tpa: one row per TPA cell, typed
    r.curves            # learning curves, long format
    r.provenance        # engine version, commit, CPU class, profile text, ...
    sirl_bench.datasets("train.h5")["grid"]["seeds"]["s0"]["queries"]["similarity"]
    sirl_bench.write_embeddings("emb.h5", {("grid", 0, 100): Z})   # Z [T, d]
"""
from .results import (FLAG_COLUMNS, PROTOCOLS, SCHEMA_VERSIONS, Results, ResultsError,  # noqa: F401
                      claims, datasets, embedding_name, filled, open, study_analysis, typed,
                      write_embeddings)

__all__ = ["FLAG_COLUMNS", "PROTOCOLS", "SCHEMA_VERSIONS", "Results", "ResultsError", "claims",
           "datasets", "embedding_name", "filled", "open", "study_analysis", "typed",
           "write_embeddings"]
__version__ = "0.20.0"
