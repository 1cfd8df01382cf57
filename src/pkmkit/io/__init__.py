"""Files: batch CSV tables and JSON-ready conversion of results."""

from pkmkit.io.csv_io import read_table, write_table
from pkmkit.io.json_io import to_jsonable

__all__ = ["read_table", "to_jsonable", "write_table"]
