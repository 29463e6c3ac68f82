"""sirl_bench: read sirl-bench results files as typed pandas DataFrames, and write the embeddings
file `sirl evaluate` scores.

    import sirl_bench
    r = sirl_bench.open("out/quick.h5")
    r.tables["tpa"]     # or r.tpa: one row per TPA cell, typed
    r.curves            # learning curves, long format
    r.provenance        # engine version, commit, CPU class, profile text, ... (typed)
    d = sirl_bench.datasets("train.h5")          # read on demand: attributes without arrays
    d["grid"]["attrs"]["seeds"]                  # [0, 1]; "hyper": {"phi.hidden": [128, 128], ...}
    d["grid"]["seeds"]["s0"]["queries"]["similarity"]
    sirl_bench.embedding_keys("train.h5")        # {("grid", 0, 100): "/grid/s0/N100", ...}
    sirl_bench.write_embeddings("emb.h5", {("grid", 0, 100): Z})   # Z [T, d]
    sirl_bench.write_environment("mine.h5", X, PHI, names=[...], name="mine")  # → its xxh3
"""
from .attributes import ATTRIBUTE_TYPES, HYPER_TYPES, Hyper, parse_hyper  # noqa: F401
from .environment_file import write_environment  # noqa: F401
from .lazy import Datasets, Group  # noqa: F401
from .results import (FLAG_COLUMNS, PROTOCOLS, SCHEMA_VERSIONS, Results, ResultsError,  # noqa: F401
                      claims, datasets, embedding_keys, embedding_name, filled, open,
                      study_analysis, typed, write_embeddings)

__all__ = ["ATTRIBUTE_TYPES", "Datasets", "FLAG_COLUMNS", "Group", "HYPER_TYPES", "Hyper",
           "PROTOCOLS", "Results", "ResultsError", "SCHEMA_VERSIONS", "claims",
           "datasets", "embedding_keys", "embedding_name", "filled", "open", "parse_hyper",
           "study_analysis", "typed", "write_embeddings", "write_environment"]
__version__ = "0.29.2"
