"""The live loop's output: one line per prediction, CSV or JSON lines, flushed as it is written so
a person or a robot reading the other end sees each prediction when it is made.

A file output is written beside its name (`<name>.partial`) and renamed when the stream ends
cleanly; a stream stopped by bad input (exit 2) leaves no file, as predict.py's batch side.
"""
import csv
import json
import os
import sys
from pathlib import Path

FORMATS = ("csv", "jsonl")


class Writer:
    def __init__(self, output: str, fmt: str, columns: list[str], holds_lists: bool = False):
        self.columns, self.fmt, self.holds_lists = columns, fmt, holds_lists
        if output == "-":
            self.file, self.path, self.partial = sys.stdout, None, None
        else:
            self.path = Path(output)
            self.partial = self.path.with_name(self.path.name + ".partial")
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.file = open(self.partial, "w", newline="", encoding="utf-8")
        self._csv = csv.writer(self.file, lineterminator="\n")
        if fmt == "csv":
            self._csv.writerow(columns)
            self.file.flush()

    def write(self, rows) -> None:
        """rows: value lists in the column order; lists inside a row (a frame's contacts, when
        `holds_lists`) are ';'-joined in CSV and kept as lists in JSON."""
        if self.fmt == "csv":
            if self.holds_lists:
                rows = [[";".join(map(str, v)) if isinstance(v, list) else v for v in row] for row in rows]
            self._csv.writerows(rows)
        else:
            self.file.write("".join(json.dumps(dict(zip(self.columns, row))) + "\n" for row in rows))
        self.file.flush()

    def finish(self, keep: bool) -> None:
        """Close a file output: renamed to its name when `keep`, removed otherwise."""
        if self.path is None:
            self.file.flush()
            return
        self.file.close()
        if keep:
            os.replace(self.partial, self.path)
        else:
            self.partial.unlink(missing_ok=True)
