"""The methods as a results file's /methods declares them (engine/method_catalog.cpp), for the
report's code run on tables a test makes without a file: figures.load_styles(Declared).
tests/reader.py checks that a file the engine writes declares the same."""
import pandas as pd

COLUMNS = ["label", "colour", "role", "queries", "figure_order", "catalog_order", "vae",
           "best_frozen", "accepts_vae", "selection", "selection_order", "dashes"]
ROWS = {
    "sirl": ["SIRL", "#d62728", "sirl", "similarity", 0, 0, False, True, True],
    "sirl+vae": ["SIRL+VAE", "#ff9896", "sirl", "similarity", 1, 0, True, True, True],
    "vae": ["VAE", "#2ca02c", "baseline", "", 2, 1, False, False, False],
    "multipref10": ["MultiPref-10", "#1f77b4", "baseline", "preference", 3, 2, False, False, True],
    "multipref50": ["MultiPref-50", "#17becf", "baseline", "preference", 4, 3, False, False, True],
    "singlepref": ["SinglePref", "#9467bd", "baseline", "preference", 5, 4, False, False, True],
    "random": ["Random", "#7f7f7f", "baseline", "", 6, 5, False, False, False],
    "truth": ["truth φ* (ceiling)", "#000000", "reference", "", -1, 7, False, True, False],
    "raw": ["raw input (floor)", "#555555", "reference", "", -1, 8, False, True, False],
}
DASHES = {"truth": "6 3", "raw": "1 1.5"}


class Declared:
    path = "<synthetic tables>"
    methods = pd.DataFrame.from_dict(
        {k: v + ["uniform", 0, DASHES.get(k, "")] for k, v in ROWS.items()},
        orient="index", columns=COLUMNS)
