"""Files: batch tables (CSV, Parquet, Feather through pyarrow), atomic output files, and
JSON-ready conversion of results.

The table functions are imported on first use (pyarrow is only needed by batch commands).
"""

from pkmkit.io.atomic import atomic_path, write_text_atomic
from pkmkit.io.json_io import to_jsonable

__all__ = ["Labels", "TableReader", "TableWriter", "atomic_path", "read_table", "to_jsonable",
           "write_table", "write_text_atomic"]

_TABLE = {"Labels", "TableReader", "TableWriter", "read_table", "write_table"}


def __getattr__(name: str):
    if name in _TABLE:
        from pkmkit.io import table

        return getattr(table, name)
    raise AttributeError(f"module 'pkmkit.io' has no attribute {name!r}")
