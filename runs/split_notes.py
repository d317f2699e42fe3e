"""What a run's split kept apart, in words that fit the data the run read.

data/splits/indices.py's SPLIT_NOTES describe a simulated sheet ("every repeat of a
position-depth pair on one side"); a user's table has no positions unless it says so: its
grouped split keeps the rows that share data.group_columns together, or, with none named, each
row is its own group. metrics.json's `data.split_note` is this note.
"""

TABLE_NOTES = {"random": "rows drawn at random (no grouping): rows of one press or object may fall on both sides"}


def split_note(summary: dict, group_columns: list[str] | None) -> str:
    """The note for `summary` (a datamodule's summary()): a scene's as the datamodule gives it,
    a user's table's from its own group columns."""
    note = summary.get("split_note", "")
    if summary.get("source", {}).get("source") != "table":
        return note
    split = summary.get("split")
    if split == "grouped":
        if group_columns:
            return (f"rows that share {', '.join(group_columns)} (data.group_columns) kept on one side "
                    "(no group shared between train, validation and test)")
        return ("each row its own group (no data.group_columns): rows drawn at random, so repeats of one "
                "press may fall on both sides; name the columns that identify a press in data.group_columns")
    return TABLE_NOTES.get(split, note)
