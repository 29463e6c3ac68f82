"""The one exception the reader raises for a file it cannot read."""


class ResultsError(ValueError):
    """A file this reader cannot read: not a results file, a schema it does not know, or a file
    that fails its checks (checksums, structure): one line for the user."""
