"""CAN log files: the formats radarnode writes and reads back, and a reader that survives a damaged file.

Every format python-can writes is either written *and* read back, or refused before a run starts:

========================  ===================================================  ============================
suffix                    format (python-can class)                            notes
========================  ===================================================  ============================
``.blf``                  Vector Binary Logging Format (BLFWriter/BLFReader)
``.asc``                  Vector ASCII (ASCWriter/ASCReader)                   ``.asc.gz`` too
``.log``                  candump -L text (CanutilsLogWriter/Reader)           ``.log.gz`` too
``.csv``                  python-can's CSV (CSVWriter/CSVReader)               ``.csv.gz`` too
``.trc``                  PEAK PCAN-View trace 2.1 (TRCWriter/TRCReader)       ``.trc.gz`` too
``.db``                   SQLite, table ``messages`` (SqliteWriter/Reader)
``.mf4``                  ASAM MDF 4 (MF4Writer/MF4Reader)                     needs ``radarnode[mf4]``
``.txt``                  python-can's Printer: a print-out no reader reads    refused
========================  ===================================================  ============================

python-can itself refuses ``.blf.gz`` and ``.db.gz``. :func:`read_frames` reads any of them and keeps going past
damage: a record it cannot parse — a line of a text log that is cut off or garbled, a frame whose DLC does not
match its data, a BLF object that is not where the file says — is skipped and counted, and reading resumes with
the next line (text formats) or the next BLF object; a damaged compressed stream, SQLite or MDF file ends the
reading there. :class:`ReadReport` says how many frames were read and where the first bad record is.
"""

from __future__ import annotations

import contextlib
import gc
import gzip
import logging
import os
import re
import struct
import sys
import time
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import can
from can.io.asc import ASCReader
from can.io import blf
from can.io.blf import BLFReader
from can.io.canutils import CanutilsLogReader
from can.io.csv import CSVReader
from can.io.trc import TRCReader

from radarnode.errors import FileError, UsageError

class _AscReader(ASCReader):
    """python-can's ASC reader, less the frame its header parser swallows: the header ends at the first line that is
    no header line, which python-can has taken by then — a file without ``internal events logged`` (a tool other than
    python-can or CANoe, a hand-written one) silently lost its first frame (an independent tester's finding). That
    line is given back to the reader's lines (:class:`_Lines`)."""

    def _extract_header(self) -> None:
        lines = self.file
        taken: list[str] = []

        def watched():
            for line in lines:
                taken.append(line)
                yield line

        self.file = watched()
        try:
            super()._extract_header()
        finally:
            self.file = lines
        if taken and isinstance(lines, _Lines) and not _ASC_HEADER.match(taken[-1]):
            lines.replay.insert(0, taken[-1])


#: the lines python-can's ASC header parser takes as header: the date, the base, a comment, the events line
_ASC_HEADER = re.compile(r"\s*(date\s|base\s|//|(no)?\s*internal\s+events\s+logged)", re.IGNORECASE)

TEXT_READERS = {".asc": _AscReader, ".csv": CSVReader, ".log": CanutilsLogReader, ".trc": TRCReader}
#: every format radarnode writes and reads back; ``.mf4`` only with asammdf installed
FORMATS = (".asc", ".blf", ".csv", ".db", ".log", ".trc", ".asc.gz", ".csv.gz", ".log.gz", ".trc.gz", ".mf4")
#: formats whose files number their channels from 1 (Vector's ASC and BLF, PEAK's TRC): python-can's writers store a
#: channel ``can0`` or ``0`` as 1. Its ASC and BLF readers give the file's number less one; :func:`read_frames` gives
#: the file's own number for every one of them (an ASC log's channel 1 was read as 0: ``decode --channel 1`` found
#: nothing, an independent tester's finding)
ONE_BASED_CHANNELS = frozenset({".asc", ".asc.gz", ".blf", ".trc", ".trc.gz"})
_READ_LESS_ONE = frozenset({".asc", ".asc.gz", ".blf"})
MAX_BAD_WITHOUT_A_FRAME = 1000      # a file that yields only bad records is not a log of this format
TOO_MANY_BAD = f"{MAX_BAD_WITHOUT_A_FRAME} bad records and not one frame: not a log of this format"
#: python-can's readers and the Message constructor raise these on a record they cannot parse
RECORD_ERRORS = (ValueError, IndexError, KeyError, TypeError, struct.error, AttributeError, OverflowError,
                 UnicodeError, can.CanError)

logger = logging.getLogger(__name__)


def mf4_available() -> bool:
    """Whether python-can can write and read MF4 here (its optional dependency asammdf is installed)."""
    from can.io import mf4
    return getattr(mf4, "asammdf", None) is not None


class _SqliteWriter(can.io.SqliteWriter):
    """python-can's SqliteWriter, whose ``stop`` keeps every frame.

    Its thread writes in batches of ``MAX_BUFFER_SIZE_BEFORE_WRITES`` (500); a ``stop`` that comes while more
    than a batch waits in its queue ends the thread after the current batch and the rest is lost (a run
    rendered faster than SQLite writes). Here ``stop`` waits until the thread has taken everything queued."""

    def stop(self) -> None:
        thread = getattr(self, "_writer_thread", None)
        buffer = getattr(self, "buffer", None)
        while buffer is not None and thread is not None and thread.is_alive() and not buffer.empty():
            time.sleep(0.005)
        super().stop()


class _BlfWriter(can.io.BLFWriter):
    """python-can's BLFWriter, a classic CAN frame packed in one ``struct`` call instead of four.

    ``on_message_received`` costs about 10 µs a frame in python-can (the channel parsed by a regular
    expression, the object's two headers and the frame packed separately), as much as the node takes to encode a
    cycle's object list; here the channel's number is kept and the 48 bytes of a CAN_MESSAGE object (object
    header, v1 header, frame) are one pack. The bytes, the object's time stamp (nanoseconds from the file's
    start, truncated to the millisecond as python-can does) and the containers are python-can's; error frames
    and CAN FD go through python-can's own code."""

    _CAN_OBJECT = struct.Struct("<4sHHLL" "LHHQ" "HBBL8s")       # OBJ_HEADER_BASE, OBJ_HEADER_V1, CAN_MSG

    def __init__(self, path, **kwargs) -> None:
        super().__init__(path, **kwargs)
        self._channels: dict = {}

    def on_message_received(self, msg: can.Message) -> None:
        if msg.is_error_frame or msg.is_fd or msg.timestamp is None:
            super().on_message_received(msg)
            return
        channel = self._channels.get(msg.channel)
        if channel is None:
            number = can.util.channel2int(msg.channel)
            channel = self._channels[msg.channel] = self.channel if number is None else number + 1
        arb_id = msg.arbitration_id | (blf.CAN_MSG_EXT if msg.is_extended_id else 0)
        flags = (blf.REMOTE_FLAG if msg.is_remote_frame else 0) | (0 if msg.is_rx else blf.DIR)
        timestamp = msg.timestamp
        if self.start_timestamp is None:
            self.start_timestamp = int(timestamp * 1000) / 1000
        self.stop_timestamp = timestamp
        since = int((timestamp - self.start_timestamp) * 1e9)
        self._buffer.append(self._CAN_OBJECT.pack(b"LOBJ", 32, 1, 48, blf.CAN_MESSAGE, blf.TIME_ONE_NANS, 0, 0,
                                                  max(since, 0), channel, flags, msg.dlc, arb_id, bytes(msg.data)))
        self._buffer_size += 48
        self.object_count += 1
        if self._buffer_size >= self.max_container_size:
            self._flush()


def open_writer(path: str):
    """python-can's writer for the file's suffix (``can.Logger``), with :class:`_SqliteWriter` for ``.db`` and
    :class:`_BlfWriter` for ``.blf``."""
    fmt = log_format(path)
    if fmt == ".db":
        return _SqliteWriter(path)
    if fmt == ".blf":
        return _BlfWriter(path)
    if fmt.endswith(".gz"):
        # the writer of the format before .gz on a gzip stream, as can.Logger makes it: but chosen by the last two
        # suffixes only (can.Logger reads every suffix of the name, and refused 'drive.2026-12-01.log.gz')
        import gzip
        from can.io.generic import TextIOMessageWriter
        from can.io.logger import MESSAGE_WRITERS

        writer = MESSAGE_WRITERS[fmt[:-3]]
        return writer(file=gzip.open(path, mode="wt" if issubclass(writer, TextIOMessageWriter) else "wb"))
    return can.Logger(path)


def log_format(path: str | os.PathLike) -> str:
    """The format key of a file name: its suffix, lower case, with ``.gz`` the two last (``.log.gz``)."""
    p = Path(path)
    suffixes = [s.lower() for s in p.suffixes]
    if suffixes and suffixes[-1] == ".gz":
        return "".join(suffixes[-2:])
    return suffixes[-1] if suffixes else ""


def allowed_text(extra: tuple[str, ...] = ()) -> str:
    shown = [f for f in FORMATS if f != ".mf4"] + [".mf4 (with radarnode[mf4])"] + list(extra)
    return "a file name ending in " + " ".join(shown)


def check_stem(path: str, option: str, known) -> None:
    """A UsageError naming the option when the output's name is one of the suffixes ``known`` alone (``.blf``,
    ``sub/.log.gz``): a hidden file's name, whose suffix pathlib does not see ('.blf' has none, '.log.gz' has '.gz'),
    so that a command took it for no format or another ("the suffix '(none)'" puzzled a tester; ``decode -o .csv``
    wrote text into it). Another hidden name (``decode -o .decoded``) is left as it is."""
    name = Path(path).name
    if name.startswith(".") and Path("x" + name).suffixes != Path(name).suffixes \
            and log_format("x" + name) in tuple(known):
        raise UsageError(f"option {option}: value {path!r} is not allowed: {name!r} is a name without a stem (a hidden "
                         f"file's); expected a name before the suffix, such as run{name}")


def check_output_format(path: str, option: str, extra: tuple[str, ...] = ()) -> str:
    """The format of an output log file, or a UsageError naming the option, the value and the formats allowed.

    ``extra`` are further suffixes the command handles itself (``.mcap``). Called before any work is done."""
    check_stem(path, option, FORMATS + tuple(extra))
    fmt = log_format(path)
    if fmt in extra:
        return fmt
    if fmt == ".txt":
        raise UsageError(f"option {option}: value {path!r} is not allowed: .txt is python-can's print-out, which no "
                         f"reader reads back (use .asc or .log for text); expected {allowed_text(extra)}")
    if fmt == ".mf4" and not mf4_available():
        raise UsageError(f"option {option}: value {path!r} needs python-can's MF4 support (asammdf), which is not "
                         "installed: pip install 'radarnode[mf4]'; or use .blf, .asc, .log, .csv, .trc or .db")
    if fmt not in FORMATS:
        what = f"no CAN log format has the suffix {fmt!r}" if fmt else f"{Path(path).name!r} has no suffix"
        raise UsageError(f"option {option}: value {path!r} is not allowed: {what}; expected {allowed_text(extra)}")
    return fmt


#: the earliest start time python-can's BLF writer stores (1990-01-01 UTC; an earlier one is written as no date)
BLF_EARLIEST_START_S = 631152000.0


def check_start_time(path: str, start_time_s: float, option: str) -> None:
    """A UsageError naming the option when the log format of ``path`` cannot give ``start_time_s`` back to a reader.

    An ASC file holds its start as a local date and time (``Begin Triggerblock``) and every frame's offset from it;
    python-can's reader gives the offsets (times from 0), and its writer puts the milliseconds unpadded (5 ms as
    ``.5``), the local time one hour of the year twice: the start is not kept, and a log rendered from another start
    than 0 would be read back from 0 (an independent tester's finding). python-can's BLF writer stores no start date
    before 1990 (``BLF_EARLIEST_START_S``): a start time between 0 and that is read back as 0."""
    fmt = log_format(path)
    if fmt == ".blf" and 0.0 < start_time_s < BLF_EARLIEST_START_S:
        raise UsageError(f"option {option}: value {start_time_s!r} is not allowed for a .blf log: BLF keeps the start "
                         f"as a date, and python-can's writer keeps none before 1990-01-01 ({BLF_EARLIEST_START_S:.0f} "
                         "s): the frames would be read back from 0; expected 0, a Unix time from "
                         f"{BLF_EARLIEST_START_S:.0f} on, or another format (.log keeps any)")
    if fmt in (".asc", ".asc.gz") and start_time_s != 0.0:
        raise UsageError(f"option {option}: value {start_time_s!r} is not allowed for an .asc log: ASC keeps its frames' "
                         "times from the file's start (its start is a local date and time, which python-can reads "
                         "back as 0), so they would be read back from 0; expected 0, or .blf or .log, which keep it")


#: BLF stores a frame's channel as an unsigned 16-bit number, counted from 1: python-can writes a channel name's
#: trailing number plus one (``can0`` is channel 1)
BLF_MAX_CHANNEL_NUMBER = 65534


_ASCII_NUMBER = re.compile(r"[0-9]+")


def ascii_number(text: str) -> bool:
    """Whether ``text`` is a bare number in ASCII digits (``１`` and ``-1`` are not): a channel given by its number."""
    return _ASCII_NUMBER.fullmatch(text) is not None


#: an interface name a log that numbers its channels can store: ASCII letters, digits and _, its trailing number (if
#: any) the interface's from 0, as python-can's writers read it (``can0``; ``vcan12``; ``bus``, no number: channel 1)
_INTERFACE_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*?([0-9]*)")


def file_channel(channel: str, fmt: str, option: str) -> int | None:
    """The channel number a log of format ``fmt`` that numbers its channels from 1 (ONE_BASED_CHANNELS) stores for
    ``--channel channel``: a bare (ASCII) number is the file's own, a name the interface's from 0 (``can0`` is 1, a
    name without a number 1, as python-can's writers store them); None for a format that keeps names. A UsageError
    naming the option for what is neither (``-1``, ``2.0``, ``can-1``, ``ä1``: read as a name's trailing number they
    picked another channel without a word, an independent tester's finding)."""
    if fmt not in ONE_BASED_CHANNELS:
        return None
    if ascii_number(channel):
        if int(channel) < 1:         # (decode found no frame on 0 and warned, where log refused it)
            raise UsageError(f"option {option}: value {channel!r} is not allowed for a {fmt} log: its channels are "
                             "numbered from 1; expected 1, 2, … or a name such as can0 (its channel 1)")
        return int(channel)
    m = _INTERFACE_NAME.fullmatch(channel)
    if m is None:
        raise UsageError(f"option {option}: value {channel!r} is not allowed for a {fmt} log, which numbers its "
                         "channels from 1; expected its number (1, 2, …) or an interface name of ASCII letters, digits "
                         "and _ (can0 is its channel 1)")
    return int(m.group(1)) + 1 if m.group(1) else 1


def check_channel(path: str, channel: str, option: str) -> str | int:
    """What to put in the frames' channel for a log ``path`` written with ``--channel channel``, or a UsageError
    naming the option when its format cannot store it. In a format that numbers channels from 1 (ONE_BASED_CHANNELS)
    a bare number is the file's channel, as ``decode --channel`` reads it (python-can's writers add one to it: ``1``
    was written as 2, and decode's ``--channel 1`` then found nothing, an independent tester's finding), and a name
    the interface's, from 0 (``can0`` is the file's channel 1). A BLF file takes a channel of at most
    BLF_MAX_CHANNEL_NUMBER + 1 (a name ending in at most BLF_MAX_CHANNEL_NUMBER)."""
    fmt = log_format(path)
    number = file_channel(channel, fmt, option)        # (a name such a format cannot store is refused)
    if fmt in (".log", ".log.gz") and not re.fullmatch(r"[!-~]+", channel):
        # a candump line names its interface in printable ASCII: can１ or ä1 were written, and decode then read none
        # of the file's lines (an independent tester's finding)
        raise UsageError(f"option {option}: value {channel!r} is not allowed for a {fmt} log: a candump line names "
                         "its interface in printable ASCII without spaces; expected such a name (can0)")
    if number is None:
        return channel
    top = BLF_MAX_CHANNEL_NUMBER + 1 if fmt == ".blf" else None
    if ascii_number(channel):               # (0 was refused by file_channel)
        if top is not None and number > top:
            raise UsageError(f"option {option}: value {channel!r} is not allowed for a {fmt} log: BLF stores the "
                             f"channel as a 16-bit number, from 1; expected 1…{top} or a name such as can0 (its "
                             "channel 1)")
        return number - 1                  # (the writer adds the one back)
    if top is not None and number > top:   # the name's trailing number plus one
        raise UsageError(f"option {option}: value {channel!r} is not allowed for a .blf log: BLF stores the channel "
                         f"as a 16-bit number (the name's trailing number plus one); expected a name ending in "
                         f"0…{BLF_MAX_CHANNEL_NUMBER} or in no number")
    return channel


def check_input_format(path: str, what: str) -> str:
    """The format of an input log file by its name, or a UsageError for a suffix no reader here knows.
    ``what`` names the argument (``argument FILE``)."""
    fmt = log_format(path)
    if fmt not in FORMATS:
        hint = " (.txt is python-can's print-out, which no reader reads)" if fmt == ".txt" else ""
        raise UsageError(f"{what}: value {path!r} is not allowed{hint}; expected a CAN log file ending in "
                         + " ".join(FORMATS))
    if fmt == ".mf4" and not mf4_available():
        raise UsageError(f"{what}: value {path!r} needs python-can's MF4 support (asammdf), which is not installed: "
                         "pip install 'radarnode[mf4]'")
    return fmt


def check_input(path: str, what: str) -> str:
    """The format of an input log file; UsageError for a suffix no reader knows (:func:`check_input_format`),
    FileError for a file that is missing, a directory, unreadable or empty."""
    fmt = check_input_format(path, what)
    p = Path(path)
    try:
        st = p.stat()
    except OSError as exc:
        raise FileError(f"{what}: cannot read {path!r}: {exc.strerror or exc}") from None
    if p.is_dir():
        raise FileError(f"{what}: cannot read {path!r}: it is a directory; expected a CAN log file")
    try:
        with open(p, "rb"):
            pass
    except OSError as exc:
        raise FileError(f"{what}: cannot read {path!r}: {exc.strerror or exc}") from None
    if st.st_size == 0 and p.is_file():
        raise FileError(f"{what}: {path!r} is empty; expected a CAN log ({fmt})")
    return fmt


@dataclass
class ReadReport:
    """What :func:`read_frames` made of a file."""

    path: str
    fmt: str
    frames: int = 0
    bad: int = 0                      # records skipped
    first_bad: str | None = None      # where the first one is and why: "line 12: …", "byte 4096: …"
    cut_short: str | None = None      # the reading ended early: where and why (the rest of the file was not read)

    def skip(self, where: str, reason: object) -> None:
        self.bad += 1
        if self.first_bad is None:
            self.first_bad = f"{where}: {_reason(reason)}"

    def stop(self, where: str, reason: object) -> None:
        self.cut_short = f"{where}: {_reason(reason)}"
        if self.first_bad is None:
            self.first_bad = self.cut_short

    def hopeless(self, where: str) -> bool:
        """Whether ``MAX_BAD_WITHOUT_A_FRAME`` records were bad and none was a frame, whoever refused them (a line
        check, a reader, the frame check): then the reading stops at ``where`` (said once) — the file is no log of
        its format."""
        if self.frames or self.bad < MAX_BAD_WITHOUT_A_FRAME:
            return False
        if self.cut_short is None:
            self.stop(where, TOO_MANY_BAD)
        return True

    @property
    def damaged(self) -> bool:
        return self.bad > 0 or self.cut_short is not None

    def message(self, what: str) -> str:
        """One line for an ``error:``: what was read and where the damage starts."""
        if self.frames == 0 and not self.damaged:
            return f"{what}: {self.path!r} holds no CAN frame; expected a log with at least one frame"
        if self.frames == 0:
            ended = f"; reading ended at {self.cut_short}" if self.cut_short not in (None, self.first_bad) else ""
            return (f"{what}: {self.path!r} holds no frame a {self.fmt} reader can read; first bad record at "
                    f"{self.first_bad}{ended}")
        parts = [f"{what}: {self.path!r} is damaged: first bad record at {self.first_bad}"]
        if self.bad:
            parts.append(f"{self.bad} bad record{'s' if self.bad != 1 else ''} skipped")
        if self.cut_short is not None and self.cut_short != self.first_bad:
            parts.append(f"reading ended at {self.cut_short}")
        elif self.cut_short is not None:
            parts.append("the rest of the file could not be read")
        parts.append(f"{self.frames} frames read")
        return "; ".join(parts)


def _reason(exc: object) -> str:
    if isinstance(exc, BaseException):
        text = str(exc).strip() or type(exc).__name__
        return text if len(text) <= 120 else text[:119] + "…"
    return str(exc)


def read_frames(path: str, report: ReadReport) -> Iterator[can.Message]:
    """The frames of a log file, skipping and counting (in ``report``) what cannot be read.

    The file must have passed :func:`check_input`. Errors of the code that consumes the frames pass through. A
    frame's channel is the one the file names (an ASC, BLF or TRC log's numbers from 1: ONE_BASED_CHANNELS).
    """
    fmt = report.fmt
    base = fmt[:-3] if fmt.endswith(".gz") else fmt
    if base in TEXT_READERS:
        frames = _TextFrames(path, fmt, TEXT_READERS[base], report)
    elif fmt == ".blf":
        frames = _BlfFrames(path, report)
    elif fmt == ".db":
        frames = _WholeFrames(path, report, can.io.SqliteReader, "row")
    elif fmt == ".mf4":
        frames = _WholeFrames(path, report, can.io.MF4Reader, "frame")
    else:                                  # pragma: no cover - check_input refuses it
        raise UsageError(f"{path!r}: no reader for {fmt!r}")
    less_one = fmt in _READ_LESS_ONE
    for msg in frames:
        problem = _frame_problem(msg)
        if problem is not None:
            report.skip(frames.where(), problem)
            if report.hopeless(frames.where()):
                return
            continue
        if less_one and isinstance(msg.channel, int) and not isinstance(msg.channel, bool):
            msg.channel += 1                 # the file's own number
        report.frames += 1
        yield msg


#: the data lengths a CAN FD frame can have (its DLC codes 0–8 bytes, then 12, 16, 20, 24, 32, 48, 64)
CAN_FD_LENGTHS = frozenset((*range(9), 12, 16, 20, 24, 32, 48, 64))


def _frame_problem(msg: can.Message) -> str | None:
    """Why a frame a reader produced cannot be on a CAN bus (a garbled or cut-off record), or None."""
    # a cut-off SQLite row comes back with None where a column was lost: every field is checked for its type (a
    # timestamp that is a number but not finite is the decoder's to write as null and count, not a bad record)
    if isinstance(msg.timestamp, bool) or not isinstance(msg.timestamp, (int, float)):
        return f"timestamp {msg.timestamp!r} is not a number"
    if msg.is_error_frame:
        return None
    if not isinstance(msg.arbitration_id, int):
        return f"CAN ID {msg.arbitration_id!r} is not a number"
    if msg.arbitration_id < 0 or msg.arbitration_id > (0x1FFFFFFF if msg.is_extended_id else 0x7FF):
        return f"CAN ID 0x{msg.arbitration_id:X} is out of range"
    if msg.is_remote_frame:          # no data: the DLC is a 4-bit field on the wire (9–15 ask for 8 bytes)
        return None if isinstance(msg.dlc, int) and 0 <= msg.dlc <= 15 else f"remote frame with DLC {msg.dlc!r}"
    if msg.data is None or not isinstance(msg.dlc, int):
        return f"DLC {msg.dlc!r} with data {msg.data!r}"
    n = len(msg.data)
    if msg.is_fd:                    # a length CAN FD's DLC codes, and the frame's DLC that length
        if n not in CAN_FD_LENGTHS:
            return f"CAN FD frame of {n} data bytes (CAN FD has 0–8, 12, 16, 20, 24, 32, 48 or 64)"
        return None if msg.dlc == n else f"CAN FD frame with DLC {msg.dlc} and {n} data bytes"
    if not 0 <= msg.dlc <= 8 or n != msg.dlc:
        return f"DLC {msg.dlc} with {n} data bytes"
    return None


# --- text formats: line by line, a bad line skipped --------------------------------------------------------


class _StreamError(Exception):
    """Reading the file itself failed (a damaged compressed stream, an I/O error): nothing after it is readable."""


class _Lines:
    """The lines of a text log for python-can's readers, counted; the preamble is replayed after a restart.

    A last line without a line end is a record cut off (a truncated file): it is held back and reported instead
    of being parsed into a wrong frame."""

    def __init__(self, f, report: ReadReport, check=None) -> None:
        self._f = f
        self._report = report
        # line -> (None, the line as the reader takes it), or (why the line is no record of the format, None)
        self._check = check
        self.lineno = 0             # lines of the file handed out so far
        self.replay: list[str] = []
        self.recording: list[str] | None = []   # lines read before the first frame (headers), while recording
        self.last: str | None = None            # the line handed out last (the one a reader's frame came from)

    def __iter__(self):
        return self

    def __next__(self) -> str:
        while True:                 # (a loop, not a recursion: thousands of bad lines in a row)
            line = self._next_line()
            if line is not None:
                return line

    def _next_line(self) -> str | None:
        """The next line for the reader, or None where the line was refused (counted in the report)."""
        if self._report.hopeless(f"line {self.lineno}"):
            raise StopIteration
        if self.replay:
            self.last = self.replay.pop(0)
            return self.last
        try:
            line = next(self._f)
        except StopIteration:
            raise
        except (OSError, EOFError, zlib.error, gzip.BadGzipFile) as exc:
            raise _StreamError(exc) from None
        self.lineno += 1
        if not line.endswith(("\n", "\r")) and line.strip():
            self._report.skip(f"line {self.lineno}", "the line is cut off (no line end): the file is truncated")
            raise StopIteration
        if self._check is not None:
            problem, line = self._check(line)
            if problem is not None:
                self._report.skip(f"line {self.lineno}", problem)
                return None
        if self.recording is not None:
            self.recording.append(line)
        self.last = line
        return line

    def close(self) -> None:        # python-can's readers close their file when done; the caller closes this one
        pass


_ASC_LINE = re.compile(r"\s*($|//|date\s|base\s|(no\s+)?internal\s+events\s+logged|begin\s+triggerblock|"
                       r"end\s+triggerblock|\d+\.\d+\s)", re.IGNORECASE)


#: a classic CAN frame event: time, channel, ID, direction, d or r — its direction must be Rx or Tx
_ASC_FRAME = re.compile(r"\s*\d+\.\d+\s+\d+\s+[0-9A-Fa-f]+x?\s+(\S+)\s+[dr]\s", re.IGNORECASE)
#: a line that begins as a classic CAN frame event (time, a channel number, a hex ID) ...
_ASC_FRAME_START = re.compile(r"\s*\d+\.\d+\s+\d+\s+[0-9A-Fa-f]+x?(\s|$)", re.IGNORECASE)
#: ... must be one whole: direction, then d, the DLC and that many two-digit bytes, or r and an optional DLC; Vector's
#: named fields (Length = …, BitCount = …) may follow
_ASC_FRAME_WHOLE = re.compile(r"\s*\d+\.\d+\s+\d+\s+[0-9A-Fa-f]+x?\s+(rx|tx)\s+(d\s+([0-9a-f])((?:\s+[0-9a-f]{2})*)"
                              r"|r(?:\s+[0-9a-f])?)(\s+[a-z].*)?\s*$", re.IGNORECASE)
#: a line laid out as a classic CAN frame event (time, a channel number, a token, Rx or Tx): its token must be a hex ID
_ASC_FRAME_LIKE = re.compile(r"\s*\d+\.\d+\s+\d+\s+(\S+)\s+(rx|tx)\s", re.IGNORECASE)
_ASC_ID = re.compile(r"[0-9A-Fa-f]+x?", re.IGNORECASE)
#: a frame event whose channel is not a number
_ASC_BAD_CHANNEL = re.compile(r"\s*\d+\.\d+\s+(?!canfd\b)(\S*[^\d\s]\S*)\s+[0-9A-Fa-f]+x?\s+(rx|tx)\s",
                              re.IGNORECASE)


def _asc_line_problem(line: str) -> str | None:
    """python-can's ASC reader passes over any line it does not know (events it does not parse); a line that is
    none of the ASC grammar's — neither a header, a comment, a trigger block's start or end nor a timestamped
    event —, a frame event that is not whole (its direction neither Rx nor Tx, none, a channel that is not a
    number, the line cut short, data bytes not of two digits or not as many as its DLC says: the reader drops some of
    those without a word and reads others wrong), or a line that holds control characters or bytes that are not
    text, is damage, and reported as such."""
    if "\ufffd" in line or any(c < " " and c not in "\t\r\n" for c in line):
        return "not text (control characters or invalid UTF-8)"
    if not _ASC_LINE.match(line):
        return f"not an ASC line: {line.strip()[:40]!r}"
    frame = _ASC_FRAME.match(line)
    if frame and frame.group(1).lower() not in ("rx", "tx"):
        return f"a frame whose direction is {frame.group(1)!r}, not Rx or Tx: {line.strip()[:40]!r}"
    if _ASC_FRAME_START.match(line):
        whole = _ASC_FRAME_WHOLE.match(line)
        if not whole:
            return f"not a whole CAN frame line: {line.strip()[:40]!r}"
        if whole.group(3) is not None and len(whole.group(4).split()) != int(whole.group(3), 16):
            return f"a frame whose data bytes are not its DLC's {int(whole.group(3), 16)}: {line.strip()[:40]!r}"
    elif _ASC_BAD_CHANNEL.match(line):
        return f"a frame whose channel is not a number: {line.strip()[:40]!r}"
    else:
        like = _ASC_FRAME_LIKE.match(line)
        if like and not _ASC_ID.fullmatch(like.group(1)):
            # (python-can's reader passes over it as an event it does not know: a frame lost without a word)
            return f"a frame whose ID {like.group(1)!r} is not hexadecimal: {line.strip()[:40]!r}"
    return None


#: a TRC line: empty, a header or comment (``;``), or a record — its message number (``1)`` in version 1.x), its
#: time offset, then its fields
_TRC_LINE = re.compile(r"\s*($|;|\d+\)?\s+-?\d+(\.\d+)?\s+\S)")


def _trc_line_problem(line: str) -> str | None:
    """python-can's TRC reader parses a record whose message number is garbled and drops a line of garbage
    without a word: a line that holds control characters or bytes that are not text, or that is neither a header
    nor a record, is damage, and reported as such (as for ASC, :func:`_asc_line_problem`)."""
    if "\ufffd" in line or any(c < " " and c not in "\t\r\n" for c in line):
        return "not text (control characters or invalid UTF-8)"
    if not _TRC_LINE.match(line):
        return f"not a TRC line: {line.strip()[:40]!r}"
    return None


#: a candump log line (can-utils' ``candump -l``, python-can's CanutilsLogWriter): ``(seconds) channel frame``, then
#: optionally python-can's direction, R or T; the fields apart by spaces or tabs (ASCII: a vertical tab, a form feed or
#: a non-breaking space is no separator of the format)
_CANDUMP_LINE = re.compile(r"[ \t]*\(([^)]*)\)[ \t]+([!-~]+)[ \t]+([!-~]+)(?:[ \t]+([RTrt]))?[ \t]*$")
_HEX = re.compile(r"[0-9A-Fa-f]*")
#: the lines of a log as candump and python-can write them, which python-can's reader reads as they are, matched at
#: once (0.9 µs a line; the reader takes 4.3): a data, remote or CAN FD frame (flags 0–9), an ID of 3 hex digits or
#: of 8 below 0x20000000
_CANDUMP_PLAIN = re.compile(r"[ \t]*\([0-9]+(?:\.[0-9]+)?\)[ \t]+[!-~]+[ \t]+(?:[0-9A-Fa-f]{3}|[01][0-9A-Fa-f]{7})#"
                            r"(?:(?:[0-9A-Fa-f]{2})*|#[0-9](?:[0-9A-Fa-f]{2})*|[Rr][0-8]?)(?: [RT])?[ \t]*$")
#: the error flag of a SocketCAN CAN ID: candump writes an error frame as its 8-digit ID with this bit and the error
#: class (up to 0x1FFFFFFF), and its data bytes (8)
CAN_ERR_FLAG = 0x20000000
#: how much of a refused line its reason quotes (a typical candump line is 45–50 characters)
_QUOTE = 64
_DLC_CODE = "a DLC code after '_' (CAN CC's DLC 9–15): radarnode reads frames whose DLC is their length"


def _candump_line(line: str) -> tuple[str | None, str | None]:
    """(None, the line as python-can's reader takes it), or (why the line is no candump record, None).

    python-can's candump reader reads some lines that are no frame of the format wrong and fails on others with
    an error of its own parsing (``300##`` gave "string index out of range"): a line that is not
    ``(seconds) channel frame`` with a frame of can-utils' grammar — an ID of 3 hex digits (standard) or 8
    (extended), then ``#`` and the data bytes (two hex digits each), ``#R`` and an optional DLC, or ``##``, the
    CAN FD flags digit and the data; an error frame an 8-digit ID with the error flag and at most 8 data bytes — is
    damage, and reported with what is wrong. (A DLC or a length the bus cannot have is the frame check's,
    :func:`_frame_problem`.) A line of the grammar python-can's reader cannot take as it is (a tab before the
    direction, an FD flags digit A–F) is given to it in its plain form (:func:`_candump_plain`)."""
    if _CANDUMP_PLAIN.match(line) or not line.strip(" \t\r\n"):
        return None, line
    whole = _CANDUMP_LINE.match(line)
    problem = _candump_problem(line, whole)
    return (problem, None) if problem is not None else (None, _candump_plain(whole))


def _candump_problem(line: str, whole: re.Match | None) -> str | None:
    """:func:`_candump_line`'s check of a line that is not plain (``whole``: its match of ``_CANDUMP_LINE``, if any):
    why it is no record, or None."""
    text = line.strip()[:_QUOTE]
    if "\ufffd" in line or "\ufeff" in line or any(c < " " and c not in "\t\r\n" for c in line):
        return "not text (control characters or invalid UTF-8)"
    if not whole:
        return f"not a candump line '(seconds) channel ID#data': {text!r}"
    stamp = whole.group(1).strip(" \t")            # (blanks inside the brackets: read, as canplayer does)
    try:
        if not stamp.isascii() or "_" in stamp or " " in stamp or "\t" in stamp:
            raise ValueError
        float(stamp)                   # (one that is not finite is the decoder's to count, as python-can reads it)
    except ValueError:
        return f"time stamp {stamp!r} is not a number of seconds: {text!r}"
    can_id, sep, data = whole.group(3).partition("#")
    if not sep:
        return f"no '#' between the CAN ID and the data: {text!r}"
    if len(can_id) not in (3, 8) or not _HEX.fullmatch(can_id):
        return f"CAN ID {can_id!r} is not 3 hex digits (standard) or 8 (extended): {text!r}"
    value = int(can_id, 16)
    if len(can_id) == 8 and value > 0x1FFFFFFF and (value > 0x3FFFFFFF or not value & CAN_ERR_FLAG):
        return f"CAN ID 0x{can_id} is out of range (29 bits, or the error flag 0x20000000 and a class): {text!r}"
    error = len(can_id) == 8 and bool(value & CAN_ERR_FLAG)
    if data.startswith("##"):
        return f"a CAN XL frame ('###'): radarnode reads CAN and CAN FD frames: {text!r}"
    if data.startswith("#"):
        if error:
            return f"an error frame (CAN ID 0x{can_id}) as a CAN FD frame: {text!r}"
        if len(data) < 2 or not _HEX.fullmatch(data[1]):
            return f"a CAN FD frame without its flags digit after '##': {text!r}"
        data = data[2:]
    elif data[:1] in ("R", "r"):
        if error:
            return f"an error frame (CAN ID 0x{can_id}) as a remote frame: {text!r}"
        if "_" in data:
            return f"{_DLC_CODE}: {text!r}"
        if not re.fullmatch(r"[0-9]*", data[1:]):
            return f"a remote frame whose DLC {data[1:]!r} is not decimal digits: {text!r}"
        return None
    if "." in data:
        return f"data bytes separated by '.' (cansend's form, not a log's): {text!r}"
    if "_" in data:
        return f"{_DLC_CODE}: {text!r}"
    if not _HEX.fullmatch(data):
        return f"data {data[:16]!r} is not hex digits: {text!r}"
    if len(data) % 2:
        return f"data of an odd number ({len(data)}) of hex digits: {text!r}"
    if error and len(data) > 16:
        return f"an error frame (CAN ID 0x{can_id}) of {len(data) // 2} data bytes (at most 8): {text!r}"
    return None


def _candump_plain(whole: re.Match) -> str:
    """A line :func:`_candump_problem` accepted (its match ``whole``), as python-can's reader takes it: one space
    between the fields (its direction test wants ``" R"``/``" T"`` at the end) and an FD flags digit of 0–7 (it reads
    the digit as a decimal number; bit 3 of the flags is no flag of CAN FD's, and the reader keeps only BRS and ESI)."""
    stamp, channel, frame, direction = whole.groups()
    can_id, _, data = frame.partition("#")
    if data.startswith("#") and len(data) > 1:
        data = f"#{int(data[1], 16) & 0x7}{data[2:]}"
    stamp, tail = stamp.strip(" \t"), " " + direction.upper() if direction else ""
    return f"({stamp}) {channel} {can_id}#{data}{tail}\n"


def _candump_channel(text: str) -> int | str:
    """A candump line's interface as a frame's channel: a number as python-can's reader gives it (``1`` is 1), but a
    name of digits that is not a number's own spelling (``01``) as it is written: python-can read ``1`` and ``01`` as
    one channel, 1, so two interfaces were one bus to ``--channel`` (a tester's finding)."""
    return int(text) if ascii_number(text) and str(int(text)) == text else text


def _candump_digit_channel(msg: can.Message, line: str | None) -> can.Message:
    """``msg``, read by python-can from candump ``line`` with a channel of digits (an int): its channel as
    :func:`_candump_channel` reads the line's."""
    whole = None if line is None else _CANDUMP_LINE.match(line)
    if whole is not None:
        msg.channel = _candump_channel(whole.group(2))
    return msg


def _candump_error_frame(msg: can.Message, line: str | None) -> can.Message:
    """python-can's candump reader makes an error frame only of an ID with the bus-error class, and without its data
    and channel; any other error class (a controller's state, a lost arbitration, a transceiver's fault) became an
    extended data frame on the class's bits. ``msg`` as an error frame where its ``line`` has the error flag in its
    ID: the class as the arbitration ID, the data bytes, the channel and the direction kept."""
    if not (msg.is_error_frame or msg.is_extended_id) or line is None:     # (a standard ID: no error frame)
        return msg
    whole = _CANDUMP_LINE.match(line)
    if whole is None:
        return msg
    _, channel, frame, direction = whole.groups()
    can_id, _, data = frame.partition("#")
    if len(can_id) != 8 or not int(can_id, 16) & CAN_ERR_FLAG:
        return msg
    payload = bytes.fromhex(data)
    return can.Message(timestamp=msg.timestamp, arbitration_id=int(can_id, 16) & 0x1FFFFFFF, is_error_frame=True,
                       dlc=len(payload), data=payload, channel=_candump_channel(channel),
                       is_rx=direction not in ("T", "t"))


class _TrcWarnings(logging.Filter):
    """python-can's TRC reader logs a line it cannot parse and goes on: counted as a bad record instead."""

    def __init__(self, lines: _Lines, report: ReadReport) -> None:
        super().__init__()
        self.lines, self.report = lines, report

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno >= logging.WARNING and "Failed to parse" in record.getMessage():
            self.report.skip(f"line {self.lines.lineno}", record.getMessage())
            return False
        return True


class _TextFrames:
    def __init__(self, path: str, fmt: str, reader_cls, report: ReadReport) -> None:
        self.path, self.fmt, self.reader_cls, self.report = path, fmt, reader_cls, report
        self.lines: _Lines | None = None

    def where(self) -> str:
        return f"line {self.lines.lineno}" if self.lines is not None else "line ?"

    def __iter__(self) -> Iterator[can.Message]:
        report = self.report
        # (utf-8-sig: a byte-order mark some Windows tools write before the first line is no part of it)
        opener = (lambda: gzip.open(self.path, "rt", encoding="utf-8-sig", errors="replace")) \
            if self.fmt.endswith(".gz") else (lambda: open(self.path, encoding="utf-8-sig", errors="replace"))
        with opener() as f:
            problem = {_AscReader: _asc_line_problem, TRCReader: _trc_line_problem}.get(self.reader_cls)
            check = _candump_line if self.reader_cls is CanutilsLogReader else \
                None if problem is None else (lambda line: (problem(line), line))
            lines = self.lines = _Lines(f, report, check)
            trc_log = logging.getLogger("can.io.trc")
            quiet = _TrcWarnings(lines, report)
            trc_log.addFilter(quiet)
            try:
                preamble: list[str] = []
                while True:
                    before = lines.lineno
                    try:
                        for msg in self.reader_cls(lines):
                            if self.reader_cls is CanutilsLogReader:
                                msg = _candump_error_frame(msg, lines.last)
                                if isinstance(msg.channel, int):
                                    msg = _candump_digit_channel(msg, lines.last)
                            if lines.recording is not None:
                                # the headers a restarted reader needs: the lines before the first frame's
                                preamble, lines.recording = lines.recording[:-1], None
                            yield msg
                        return
                    except _StreamError as exc:
                        report.stop(f"line {lines.lineno + 1}", exc.__cause__ or exc.args[0])
                        return
                    except RECORD_ERRORS as exc:
                        report.skip(f"line {lines.lineno}", exc)
                        if lines.recording is not None:          # a bad line among the headers: not replayed
                            preamble, lines.recording = lines.recording[:-1], lines.recording[:-1]
                        if report.hopeless(f"line {lines.lineno}"):
                            return
                        if lines.lineno == before:
                            report.stop(f"line {lines.lineno}", "no progress past this line")
                            return
                        lines.replay = list(preamble)
            finally:
                trc_log.removeFilter(quiet)


# --- BLF: object by object, resynchronised on the next object signature ------------------------------------


class _BlfFrames:
    """A BLF file container by container, each one's frames parsed by python-can's reader (its object parser and
    the half object it carries from one container to the next). The containers are walked here, not by the reader,
    so that every kind of damage is found where it is and costs only that container:

    - a container whose signature, size, compression method or compressed data is damaged is a bad record at its
      start (python-can skipped an unknown method with a log warning and kept the half object before it, which the
      next container's data then completed into a made-up frame);
    - a container whose declared size overruns the next one (the compressed stream ends inside it) is read, and the
      next one is found by its signature from there (python-can lost it);
    - after a damaged container, the next one's data is read from its first whole object: its beginning is the end
      of an object the damaged one began (python-can's reader refused it, and every one after it);
    - a file that ends inside a container, or short of the size its header declares, is truncated."""

    def __init__(self, path: str, report: ReadReport) -> None:
        self.path, self.report = path, report
        self.pos = 0

    def where(self) -> str:
        return f"byte {self.pos}"

    def __iter__(self) -> Iterator[can.Message]:
        report = self.report
        try:
            with open(self.path, "rb") as probe:
                head = probe.read(blf.FILE_HEADER_SIZE)
        except OSError as exc:
            report.stop("byte 0", exc)
            return
        if head.startswith(b"LOGG") and len(head) < blf.FILE_HEADER_SIZE:
            # (a file cut inside its header was "not a BLF file" or one whose size field was damaged)
            report.stop(f"byte {len(head)}", f"the file ends {len(head)} bytes into its {blf.FILE_HEADER_SIZE}-byte "
                                             "header: it is truncated")
            return
        try:
            reader = BLFReader(self.path)
        except OSError as exc:
            report.stop("byte 0", exc)
            return
        except Exception as exc:  # noqa: BLE001 - struct.error, BLFParseError: not a BLF header
            # a damaged file header: the file is read from its first object, if it has one (times from the header's
            # start time where that still reads, else from 0)
            reader = _headless_reader(self.path)
            if reader is None:
                report.stop("byte 0", f"not a BLF file ({_reason(exc)})")
                return
            report.skip("byte 0", f"the file header is damaged ({_reason(exc)}); read from its first object")
        f = reader.file
        size = os.fstat(f.fileno()).st_size
        head_size = blf.OBJ_HEADER_BASE_STRUCT.size
        resume = False                           # the next container follows a damaged one: from its first object
        if f.tell() != blf.FILE_HEADER_SIZE:
            # the header's own size field is damaged (every BLF header is 144 bytes): from the first object after
            # the header's fixed fields, read from its first whole object (harmless if it is the first container)
            report.skip("byte 4", f"the file header's size field says {f.tell()} bytes, not "
                                  f"{blf.FILE_HEADER_SIZE}: it is damaged")
            first = _find_object(f, blf.FILE_HEADER_STRUCT.size, size)
            f.seek(size if first is None else first)
            resume = True

        def damaged(where: int, reason: object) -> int | None:
            """A bad record at ``where``; the offset of the next object signature after it (None: none)."""
            nonlocal resume
            report.skip(f"byte {where}", reason)
            reader._tail = b""
            resume = True
            return _find_object(f, where + 1, size)

        try:
            declared = int(reader.file_size)
            pos = f.tell()                       # after the file header
            while pos is not None and pos < size:
                self.pos = pos
                if report.hopeless(self.where()):
                    return
                f.seek(pos)
                head = f.read(head_size)
                if len(head) < head_size:
                    report.stop(f"byte {pos}", f"the file ends {len(head)} bytes into an object's header: it is "
                                               "truncated")
                    return
                signature, _, _, obj_size, obj_type = blf.OBJ_HEADER_BASE_STRUCT.unpack(head)
                if signature != b"LOBJ" or obj_size < head_size + blf.LOG_CONTAINER_STRUCT.size:
                    pos = damaged(pos, "not a BLF object (its signature or size is damaged)")
                    continue
                body = f.read(obj_size - head_size)
                if len(body) < obj_size - head_size:
                    # the file ends inside the object: truncated — or the last container's size is damaged, and its
                    # compressed data, whole, is still read
                    container = obj_type == blf.LOG_CONTAINER and len(body) > blf.LOG_CONTAINER_STRUCT.size
                    inflated = _inflate(body[blf.LOG_CONTAINER_STRUCT.size:]) if container else "not a container"
                    whole = None if isinstance(inflated, str) else inflated[0]
                    # a container cut off (a logger that lost power): the whole objects of the data its compressed
                    # stream gives up to the cut (zlib cannot check a stream without its end; each frame is checked as
                    # any other, and the object cut in two is left out)
                    data = whole if whole is not None else _inflate_cut(body) if container else b""
                    before = report.frames              # (the caller counts the frames it takes)
                    if data:
                        try:
                            yield from reader._parse_container(_from_first_object(data) if resume else data)
                        except RECORD_ERRORS + (can.io.blf.BLFParseError,):
                            pass
                    read = report.frames - before
                    report.stop(f"byte {pos}", f"the file ends inside an object of {obj_size} bytes: it is truncated"
                                               f" ({read} frames of its data before the cut were read)"
                                if whole is None else f"the object's size, {obj_size} bytes, runs past the end of "
                                                      "the file (its data was read)")
                    return
                following = pos + obj_size + obj_size % 4
                if obj_type != blf.LOG_CONTAINER:        # (python-can passes over any other top-level object)
                    pos = following
                    continue
                method, _ = blf.LOG_CONTAINER_STRUCT.unpack_from(body)
                payload = body[blf.LOG_CONTAINER_STRUCT.size:]
                if method == blf.NO_COMPRESSION:
                    data, rest = payload, b""
                elif method == blf.ZLIB_DEFLATE:
                    inflated = _inflate(payload)
                    if isinstance(inflated, str):
                        pos = damaged(pos, inflated)
                        continue
                    data, rest = inflated
                else:
                    pos = damaged(pos, f"unknown compression method {method} (damaged)")
                    continue
                if resume:
                    data = _from_first_object(data)
                    resume = False
                try:
                    for msg in reader._parse_container(data):
                        yield msg
                except RECORD_ERRORS + (can.io.blf.BLFParseError,) as exc:
                    pos = damaged(pos, exc)
                    continue
                if rest and following < size:
                    # the compressed stream ended before the size declared: that size is damaged (a bad record, though
                    # the data read is whole: zlib checked it), and the next container is where the next signature is
                    report.skip(f"byte {pos}", f"the container's size, {obj_size} bytes, is damaged: its compressed "
                                               f"data ends {len(rest)} bytes before (its frames were read)")
                    nxt = _find_object(f, pos + head_size, size)
                    pos = nxt if nxt is not None and nxt < following else following
                    continue
                pos = following
            if 0 < size < declared:
                report.stop(f"byte {size}", f"the file ends after {size} bytes, its header says {declared}: "
                                            "it is truncated")
        finally:
            reader.stop()


def _headless_reader(path: str) -> BLFReader | None:
    """python-can's BLF reader for a file whose header is damaged but that holds objects: made without reading the
    header (its start time taken where it still reads, else 0), at the header's usual size; None without objects."""
    with open(path, "rb") as probe:
        data = probe.read(1 << 20)
    if data.find(b"LOBJ") < 0:
        return None
    reader = BLFReader.__new__(BLFReader)
    reader.file = open(path, "rb")                 # noqa: SIM115 - closed by reader.stop()
    try:
        header = blf.FILE_HEADER_STRUCT.unpack_from(data.ljust(blf.FILE_HEADER_STRUCT.size, b"\0"))
        reader.start_timestamp = blf.systemtime_to_timestamp(header[14:22])
        reader.file_size = header[10]
    except Exception:  # noqa: BLE001 - the start time is damaged too
        reader.start_timestamp, reader.file_size = 0.0, 0
    reader._tail, reader._pos = b"", 0
    reader.file.seek(blf.FILE_HEADER_SIZE)
    return reader


def _inflate(payload: bytes) -> tuple[bytes, bytes] | str:
    """A container's zlib payload decompressed, and the bytes after its stream (none in a whole container), if the
    stream is whole (zlib checks it); else why not."""
    z = zlib.decompressobj()
    try:
        data = z.decompress(payload)
    except zlib.error as exc:
        return _reason(exc)
    return (data, z.unused_data) if z.eof else "its compressed data ends early"


def _inflate_cut(body: bytes) -> bytes:
    """What the compressed data of a container cut off by the end of the file decompresses to, up to the cut (empty
    if the method is not zlib, or its data is damaged before the cut)."""
    method, _ = blf.LOG_CONTAINER_STRUCT.unpack_from(body)
    payload = body[blf.LOG_CONTAINER_STRUCT.size:]
    if method == blf.NO_COMPRESSION:
        return payload
    if method != blf.ZLIB_DEFLATE:
        return b""
    try:
        return zlib.decompressobj().decompress(payload)
    except zlib.error:
        return b""


def _from_first_object(data: bytes) -> bytes:
    """A container's data from the first object that begins in it (after a damaged container, its beginning is the
    end of an object the damaged one began)."""
    first = data.find(b"LOBJ")
    return data[first:] if first >= 0 else b""


def _find_object(f, start: int, size: int) -> int | None:
    """The offset of the next BLF object signature at or after ``start``, or None."""
    f.seek(start)
    chunk_size = 1 << 16
    pos = start
    carry = b""
    while pos < size:
        data = f.read(chunk_size)
        if not data:
            return None
        buf = carry + data
        i = buf.find(b"LOBJ")
        if i >= 0:
            return pos - len(carry) + i
        carry = buf[-3:]
        pos += len(data)
    return None


# --- SQLite and MDF: read until the first damage ------------------------------------------------------------


class _WholeFrames:
    def __init__(self, path: str, report: ReadReport, open_reader, unit: str) -> None:
        self.path, self.report, self.open_reader, self.unit = path, report, open_reader, unit

    def where(self) -> str:
        return f"{self.unit} {self.report.frames + self.report.bad + 1}"

    def __iter__(self) -> Iterator[can.Message]:
        hook = sys.unraisablehook
        sys.unraisablehook = lambda unraisable: None      # asammdf's __del__ complains about a file it could not open
        reader = None
        try:
            try:
                reader = self.open_reader(self.path)
            except Exception as exc:  # noqa: BLE001 - sqlite3 and asammdf raise their own kinds on a file not theirs
                self.report.stop(f"{self.unit} 1", f"cannot be read as {self.report.fmt} ({_reason(exc)})")
            if reader is None:
                gc.collect()            # the half-built reader goes now, while its complaints are silenced
        finally:
            sys.unraisablehook = hook
        if reader is None:
            return
        try:
            it = iter(reader)
            while True:
                try:
                    msg = next(it)
                except StopIteration:
                    return
                except Exception as exc:  # noqa: BLE001 - as above, on damage mid-way
                    self.report.stop(self.where(), exc)
                    return
                yield msg
        finally:
            with contextlib.suppress(Exception):
                reader.stop()


__all__ = ["FORMATS", "ReadReport", "check_input", "check_input_format", "check_output_format", "log_format", "mf4_available",
           "open_writer", "read_frames"]
