"""Lines from a file descriptor: numbered as they arrive, bounded in memory whatever the writer's
pace, and the backlog policies (export/live/backlog.py) taking, batching or dropping them."""
import os
import threading

import pytest

from common.errors import InputError
from export.live.backlog import Backlog
from export.live.sources import READ_BYTES, LineSource, is_stream, open_source


def pipe_with(data: bytes) -> LineSource:
    read_end, write_end = os.pipe()
    writer = threading.Thread(target=lambda: (os.write(write_end, data), os.close(write_end)))
    writer.start()
    source = LineSource(read_end, "pipe", lambda: os.close(read_end))
    source.writer = writer
    return source


def test_lines_keep_their_numbers_and_a_last_line_without_newline_counts():
    source = pipe_with(b"1,2\r\n\n3,4\n5,6")
    taken = source.take(10)
    while more := source.take(10):
        taken += more
    assert [n for n, _ in taken] == [1, 2, 3, 4] and taken[-1][1] == "5,6" and taken[0][1] == "1,2\r"
    source.close()


def test_batch_takes_what_waits_and_wait_takes_one():
    source = pipe_with(b"1\n2\n3\n")
    source.writer.join()
    assert len(Backlog("wait").next_lines(source)) == 1
    assert [n for n, _ in Backlog("batch", batch=5).next_lines(source)] == [2, 3]
    source.close()


def test_drop_keeps_the_newest_and_counts_the_rest_in_bounded_memory():
    data = b"".join(b"%d,1\n" % k for k in range(1, 200_001))   # ~1.5 MB: many reads
    source = pipe_with(data)
    source.writer.join(timeout=0.1)   # a pipe holds 64 KiB: the writer blocks until read
    backlog = Backlog("drop")
    seen, most_waiting = [], 0
    while lines := backlog.next_lines(source):
        seen += lines
        most_waiting = max(most_waiting, len(source._lines))
    assert seen[-1][0] == 200_000 and len(seen) + source.dropped == 200_000
    assert most_waiting * 4 <= READ_BYTES   # never more than one read's lines held
    source.close()


def test_a_backlog_is_said_once():
    said = []
    source = pipe_with(b"1\n2\n3\n4\n")
    source.writer.join()
    backlog = Backlog("batch", batch=2, warn=said.append)
    while lines := backlog.next_lines(source):
        backlog.check(source, len(lines))
    assert len(said) == 1 and "faster than the model" in said[0]
    source.close()


def test_settings_and_sources_refused_in_one_line(tmp_path):
    with pytest.raises(InputError, match="backlog must be one of"):
        Backlog("queue")
    with pytest.raises(InputError, match="expected tcp://"):
        open_source("tcp://nowhere")
    with pytest.raises(InputError, match="no such serial device"):
        open_source(str(tmp_path / "ttyUSB9"))
    assert is_stream("-") and is_stream("tcp://:9000") and not is_stream(str(tmp_path / "rig.csv"))
