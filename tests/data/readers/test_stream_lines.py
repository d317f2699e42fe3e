"""The live stream's line format: readings with or without the rig's time stamp, a CSV header
that picks the model's columns by name, and every kind of bad line refused with why."""
import numpy as np
import pytest

from data.readers.stream_lines import BadLine, LineFormat

COLUMNS = ["a_ohm", "b_ohm"]


def test_readings_alone_or_after_a_time_stamp():
    lines = LineFormat(COLUMNS)
    stamp, readings = lines.parse("1.5,2\r\n")
    assert stamp is None and readings.tolist() == [1.5, 2.0]
    stamp, readings = lines.parse("0.25, 3, 4")
    assert stamp == 0.25 and readings.tolist() == [3.0, 4.0]


def test_blank_lines_and_comments_are_not_readings():
    lines = LineFormat(COLUMNS)
    assert lines.parse("   \n") is None and lines.parse("# firmware v2") is None
    assert lines.parse("1,2 # ok").__getitem__(1).tolist() == [1.0, 2.0]


def test_a_header_picks_the_model_columns_by_name_and_the_time_stamp():
    lines = LineFormat(COLUMNS)
    assert lines.parse("split,b_ohm,time_s,a_ohm") is None
    stamp, readings = lines.parse("test,2,0.5,1")
    assert stamp == 0.5 and readings.tolist() == [1.0, 2.0]
    with pytest.raises(BadLine, match="3 values, expected 4"):
        lines.parse("test,2,0.5")


def test_a_header_without_the_model_columns_is_refused():
    with pytest.raises(BadLine, match="without the model's column"):
        LineFormat(COLUMNS).parse("x,y")


@pytest.mark.parametrize("line, why", [
    ("1,abc", "'abc' is not a number"), ("1,nan", "'b_ohm' is nan, not finite"), ("inf,1", "not finite"),
    ("1e308,1", "beyond float32"), ("1", "1 values, expected 2"), ("1,2,3,4", "4 values, expected 2"),
    ("-1,1", "outside its physical range"), ("nan,1,2", "time stamp nan")])
def test_a_bad_line_says_why(line, why):
    lines = LineFormat(COLUMNS)
    lines.parse("0,1")   # a first line of data: no header from here on
    with pytest.raises(BadLine, match=why):
        lines.parse(line)


def test_a_column_without_a_unit_takes_any_float32():
    assert LineFormat(["cell_r0_c0"]).parse("-5")[1].tolist() == [-5.0]
    assert np.isfinite(LineFormat(["cell"]).parse("3e38")[1]).all()


def test_only_the_first_line_may_be_a_header():
    lines = LineFormat(COLUMNS)
    with pytest.raises(BadLine, match="header without"):
        lines.parse("x,y")
    assert lines.parse("1,2")[1].tolist() == [1.0, 2.0]
    with pytest.raises(BadLine, match="'a_ohm' is not a number"):
        lines.parse("a_ohm,b_ohm")
