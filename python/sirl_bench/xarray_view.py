"""A long table of a results file as an xarray.Dataset: one dimension per cell field, one data
variable per measured column (Results.to_xarray). xarray is optional (Debian: python3-xarray);
everything else in sirl_bench works without it.

A long table holds one row per cell; the Dataset puts the cells on a grid (env × variant × N ×
seed, ...), with NaN where the grid has no cell (VAE has no N, an environment ran fewer M). The
dimensions must name each row once: a file whose rows also differ in a column left out (two
teachers, hyper-parameter points) is refused naming that column, never averaged or dropped.
"""
import pandas as pd

from .errors import ResultsError

# The dimensions a table's rows are told apart by in a file of one teacher and no hyper axes.
DEFAULT_DIMS = {
    "fpe": ("env", "variant", "N", "seed"),
    "tpa": ("env", "protocol", "variant", "frozen", "N", "M", "seed"),
    "tpa_heads": ("env", "variant", "frozen", "N", "M", "seed", "head"),
    "vae_latents": ("env", "seed", "dim"),
    "curves": ("key", "head", "epoch"),
}


def _xarray():
    try:
        import xarray
    except ImportError:
        raise ImportError("to_xarray needs xarray (Debian: apt install python3-xarray); the "
                          "tables themselves are pandas DataFrames (Results.tables)") from None
    return xarray


def _plain(col: pd.Series) -> pd.Series:
    """pandas' nullable columns (Int64, boolean, string) as numpy ones xarray keeps: numbers as
    float with NaN for missing, flags and texts as objects."""
    if isinstance(col.dtype, pd.Int64Dtype) or pd.api.types.is_float_dtype(col.dtype):
        return col.astype("float64")
    if isinstance(col.dtype, (pd.BooleanDtype, pd.StringDtype)):
        return col.astype(object).where(col.notna(), None)
    return col


def frame_to_xarray(df: pd.DataFrame, dims, name="table"):
    """`df` as an xarray.Dataset over `dims` (columns of df): the other columns are its data
    variables. Raises ResultsError when a dimension is not a column or when two rows share
    every dimension's value (naming the columns that tell them apart)."""
    xr = _xarray()
    dims = list(dims)
    missing = [d for d in dims if d not in df.columns]
    if missing:
        raise ResultsError(f"{name}: no column {', '.join(missing)} to use as a dimension "
                           f"(its columns: {', '.join(df.columns)})")
    df = df.copy()
    for d in dims:  # a missing cell field (head of a one-curve training, N of VAE) is −1
        if df[d].isna().any():
            if pd.api.types.is_numeric_dtype(df[d].dtype):
                df[d] = df[d].fillna(-1)
            else:
                df[d] = df[d].astype(object).where(df[d].notna(), "")
    dup = df.duplicated(dims, keep=False)
    if dup.any():
        rows = df[dup]
        differ = [c for c in df.columns if c not in dims
                  and rows.groupby(dims, dropna=False)[c].nunique(dropna=False).max() > 1]
        hint = [c for c in differ if c in ("teacher", "hyper_point", "selection", "method", "vae",
                                           "reference", "key", "kind")] or differ[:4]
        raise ResultsError(f"{name}: {int(dup.sum())} rows share their {', '.join(dims)}; they "
                           f"differ in {', '.join(hint) or 'nothing'}: add it to dims, or filter "
                           f"the table first")
    values = [c for c in df.columns if c not in dims]
    out = pd.DataFrame({c: _plain(df[c]) for c in values})
    for d in dims:
        out[d] = _plain(df[d]).to_numpy()
    return xr.Dataset.from_dataframe(out.set_index(dims))
