"""Where a live stream's lines come from: standard input, a serial port (pyserial; a
pseudo-terminal is one too) or a TCP socket listening on localhost, read through one file
descriptor by one thread.

    input=-                          standard input (a pipe, `cat /dev/ttyACM0 | ...`)
    input=/dev/ttyACM0               a serial port (any character device), baud=115200 by default
    input=serial:///dev/ttyUSB0      the same, said explicitly
    input=tcp://:9000                listen on 127.0.0.1:9000 for one connection (port 0: any free port)
    input=tcp://0.0.0.0:9000         another address only when named

LineSource keeps the bytes read but not yet taken, split into numbered lines. It reads from the
descriptor only when fewer lines wait than one batch, so what it holds is bounded by one read
(READ_BYTES) plus a batch, whatever the rate of the input; `waiting()` says, without blocking,
whether the input is ahead of the model (the backlog that export/live/backlog.py acts on).
"""
import errno
import os
import select
import socket
import stat
import sys
import termios
from collections import deque

from common.errors import InputError

READ_BYTES = 1 << 16
LONGEST_LINE = 1 << 20   # a line longer than this is not a reading: refused rather than buffered


class LineSource:
    """Numbered text lines from a file descriptor. `number` counts every line read so far, so a
    line keeps its number whether it is predicted, skipped or dropped."""

    def __init__(self, fd: int, name: str, closer=None):
        self.fd, self.name, self._closer = fd, name, closer
        self._partial = b""
        self._lines = deque()     # (number, bytes) read but not yet taken
        self.number = 0
        self.ended = False
        self.dropped = 0

    def _read(self) -> None:
        """One read (blocking): its whole lines join the queue; the end of input ends the stream."""
        try:
            chunk = os.read(self.fd, READ_BYTES)
        except OSError as error:
            if error.errno != errno.EIO:  # EIO: the other end of a pseudo-terminal closed
                raise InputError(f"{self.name}: cannot read ({error.strerror})") from None
            chunk = b""
        if not chunk:
            self.ended = True
            if self._partial.strip():
                self._add(self._partial)
            self._partial = b""
            return
        pieces = (self._partial + chunk).split(b"\n")
        self._partial = pieces.pop()
        if len(self._partial) > LONGEST_LINE:
            raise InputError(f"{self.name}: line {self.number + 1} is longer than {LONGEST_LINE} bytes without "
                             "an end of line; is this a text stream?")
        for piece in pieces:
            self._add(piece)

    def _add(self, piece: bytes) -> None:
        self.number += 1
        self._lines.append((self.number, piece))

    def _ready(self) -> bool:
        """Whether a read would return at once (data or the end of input)."""
        return bool(select.select([self.fd], [], [], 0)[0])

    def waiting(self) -> int:
        """Lines waiting after the ones taken, topped up once without blocking: > 0 means the input
        is ahead of the model."""
        if not self._lines and not self.ended and self._ready():
            self._read()
        return len(self._lines)

    def take(self, most: int) -> list[tuple[int, str]]:
        """Up to `most` waiting lines (blocks for the first one); [] at the end of the stream."""
        while not self._lines and not self.ended:
            self._read()
        while len(self._lines) < most and not self.ended and self._ready():
            self._read()
        n = min(most, len(self._lines))
        return [(number, raw.decode("utf-8", "replace")) for number, raw in
                (self._lines.popleft() for _ in range(n))]

    def skip_to_newest(self) -> None:
        """Drop every line waiting but the newest, reading what has arrived meanwhile; `dropped`
        counts them. Memory stays one read, however far behind the model is."""
        while not self.ended and self._ready():
            self._read()
            while len(self._lines) > 1:
                self._lines.popleft()
                self.dropped += 1
        while len(self._lines) > 1:
            self._lines.popleft()
            self.dropped += 1

    def close(self) -> None:
        if self._closer is not None:
            self._closer()


def open_source(spec: str, baud: int = 115200, announce=print) -> LineSource:
    """The LineSource `spec` names (see the module's doc); `announce` says where a socket listens."""
    if spec == "-":
        try:
            return LineSource(sys.stdin.fileno(), "stdin")
        except (AttributeError, ValueError, OSError):
            raise InputError("input=-: standard input is not a file descriptor (run predict.py from a shell)") from None
    if spec.startswith("tcp://"):
        return _socket_source(spec, announce)
    path = spec.removeprefix("serial://")
    return _serial_source(path, baud)


def is_stream(spec: str) -> bool:
    """Whether input=`spec` is a live stream rather than a file read whole."""
    if spec == "-" or spec.startswith(("tcp://", "serial://")):
        return True
    try:
        return stat.S_ISCHR(os.stat(spec).st_mode) or stat.S_ISFIFO(os.stat(spec).st_mode)
    except OSError:
        return False


def _serial_source(path: str, baud: int) -> LineSource:
    if not os.path.exists(path):
        raise InputError(f"input={path}: no such serial device")
    if stat.S_ISFIFO(os.stat(path).st_mode):  # a named pipe: no port settings to make
        fd = os.open(path, os.O_RDONLY)
        return LineSource(fd, path, lambda: os.close(fd))
    try:
        import serial  # pyserial: only a serial input needs it
    except ImportError:
        raise InputError(f"input={path}: reading a serial port needs pyserial (pip install pyserial)") from None
    try:
        port = serial.Serial(path, baudrate=baud, timeout=None)
    except (serial.SerialException, ValueError, OSError) as error:
        raise InputError(f"input={path}: cannot open the serial port ({str(error).splitlines()[0][:120]})") from None
    # pyserial leaves the port non-blocking with VMIN = 0 (its own reads select first): a plain read
    # then returns b"" at once when no byte has arrived yet, which this source would take for the
    # end of the stream. Reads here block until at least one byte (VMIN = 1, VTIME = 0).
    os.set_blocking(port.fileno(), True)
    attributes = termios.tcgetattr(port.fileno())
    attributes[6][termios.VMIN], attributes[6][termios.VTIME] = 1, 0
    termios.tcsetattr(port.fileno(), termios.TCSANOW, attributes)
    return LineSource(port.fileno(), path, port.close)


def _socket_source(spec: str, announce) -> LineSource:
    host, sep, port = spec.removeprefix("tcp://").rpartition(":")
    if not sep or not port.isdigit() or int(port) > 65535:
        raise InputError(f"input={spec}: expected tcp://[host]:PORT, e.g. tcp://:9000")
    host = host or "127.0.0.1"   # localhost unless another address is named
    try:
        server = socket.create_server((host, int(port)))
    except OSError as error:
        raise InputError(f"input={spec}: cannot listen on {host}:{port} ({error.strerror})") from None
    announce(f"listening on {host}:{server.getsockname()[1]} for one connection")
    connection, _ = server.accept()
    server.close()
    return LineSource(connection.fileno(), spec, connection.close)
