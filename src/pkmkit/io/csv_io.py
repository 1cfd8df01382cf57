"""Batch tables (former CSV-only module): see :mod:`pkmkit.io.table`, which reads and writes
CSV, Parquet and Feather through pyarrow."""

from pkmkit.io.table import read_table, write_table

__all__ = ["read_table", "write_table"]
