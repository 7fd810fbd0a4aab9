"""The results of a sweep: one row per run, keyed by the hash of its configuration, kept in
``results.parquet`` and ``results.csv`` (the same rows) in the sweep's folder.

A run with a row and no error is done: a sweep run again skips it.  A failed run is run
again, and its new row takes the place of the old one.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

PARQUET = "results.parquet"
CSV = "results.csv"

# The team's scores, as the simulator's score file gives them (docs/scoring.md).
SCORE_COLUMNS = (
    "score",
    "victims_found",
    "victims_reported",
    "false_reports",
    "area_m2",
    "distance_m",
    "collisions",
    "robots_lost",
    "radio_contact_share",
    "messages_delivered",
    "messages_lost",
)
# The score of the map the team handed in (serve --team-map; docs/scoring.md "Map quality"),
# from the score file's "map": coverage, accuracy (both shares), the alignment's residual
# (metres) and the victims placed on the map within 1 m of one
MAP_COLUMNS = ("map_coverage", "map_accuracy", "map_residual_m", "map_victims")
_INT_SCORES = {
    "victims_found",
    "victims_reported",
    "false_reports",
    "collisions",
    "robots_lost",
    "messages_delivered",
    "messages_lost",
}

# Every column of a row, in order, with its type (pyarrow's name).
COLUMNS: tuple[tuple[str, str], ...] = (
    ("run_id", "string"),
    ("experiment", "string"),
    ("world", "string"),
    ("variant", "int64"),
    ("seed", "int64"),
    ("team", "string"),
    ("robots_n", "int64"),
    ("wireless", "string"),
    ("duration_s", "float64"),
    ("clock", "string"),
    ("controller", "string"),
    *((c, "int64" if c in _INT_SCORES else "float64") for c in SCORE_COLUMNS),
    *((c, "int64" if c == "map_victims" else "float64") for c in MAP_COLUMNS),
    ("time_s", "float64"),
    ("wall_s", "float64"),
    ("start_s", "float64"),
    ("setup_s", "float64"),
    ("control_s", "float64"),
    ("stop_s", "float64"),
    ("error", "string"),
    ("log", "string"),
    ("robots", "string"),
    ("config", "string"),
    ("node", "string"),
    ("finished_at", "string"),
)
COLUMN_NAMES = tuple(name for name, _ in COLUMNS)


def schema() -> Any:
    import pyarrow as pa

    return pa.schema([(name, getattr(pa, kind)()) for name, kind in COLUMNS])


def read_rows(path: str | Path) -> list[dict[str, Any]]:
    """The rows of a results folder (or of its ``results.parquet``)."""
    import pyarrow.parquet as pq

    p = Path(path)
    if p.is_dir():
        p = p / PARQUET
    return pq.read_table(p).to_pylist()


def write_rows(rows: list[dict[str, Any]], folder: str | Path) -> None:
    """``results.parquet`` and ``results.csv`` of ``rows`` in ``folder`` (each written to a
    temporary file first, then renamed: a reader never sees half a file)."""
    import pyarrow as pa
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    table = pa.Table.from_pylist([{c: r.get(c) for c in COLUMN_NAMES} for r in rows], schema=schema())
    for name, write in ((PARQUET, lambda t, p: pq.write_table(t, p)), (CSV, lambda t, p: pcsv.write_csv(t, p))):
        tmp = folder / f".{name}.tmp"
        write(table, str(tmp))
        os.replace(tmp, folder / name)


class ResultsStore:
    """The rows of a results folder, in memory, saved on :meth:`save`."""

    def __init__(self, folder: str | Path):
        self.folder = Path(folder)
        self.rows: list[dict[str, Any]] = read_rows(self.folder) if (self.folder / PARQUET).exists() else []
        self._dirty = False

    def done_ids(self) -> set[str]:
        return {r["run_id"] for r in self.rows if not r.get("error")}

    def add(self, row: dict[str, Any]) -> None:
        """Append ``row``, or replace the row of the same run (a failed run run again)."""
        for i, old in enumerate(self.rows):
            if old["run_id"] == row["run_id"]:
                self.rows[i] = row
                break
        else:
            self.rows.append(row)
        self._dirty = True

    def save(self) -> None:
        if self._dirty:
            write_rows(self.rows, self.folder)
            self._dirty = False
