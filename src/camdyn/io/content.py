"""What a file holds, judged from its first bytes.

The measurement readers use :func:`file_kind` to name a file that is empty, binary, or
in another format than its suffix says (netCDF bytes saved as ``.csv``, a CSV table
saved as ``.uff``), instead of failing deep inside a parser.
"""

from __future__ import annotations

import codecs
import re
from pathlib import Path

__all__ = ["HEAD_BYTES", "KIND_NAMES", "file_kind", "read_head", "one_line", "looks_like_text", "unmarked_utf16"]

#: Bytes read from the start of a file to judge its kind [bytes].
HEAD_BYTES = 4096

#: A readable name of every kind :func:`file_kind` returns.
KIND_NAMES = {
    "empty": "an empty file (0 bytes)",
    "hdf5": "a netCDF-4/HDF5 file",
    "netcdf3": "a classic netCDF-3 file",
    "uff": "a UFF (universal file format) text file",
    "text": "text (CSV or similar)",
    "zip": "a ZIP archive (an Excel .xlsx workbook?)",
    "xls": "an old Excel .xls workbook",
    "gzip": "a gzip-compressed file",
    "matlab": "a MATLAB .mat file",
    "pdf": "a PDF document",
    "binary": "binary data of no known format",
}

_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
_SIGNATURES = (
    (b"CDF\x01", "netcdf3"), (b"CDF\x02", "netcdf3"), (b"CDF\x05", "netcdf3"),
    (b"PK\x03\x04", "zip"), (b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1", "xls"), (b"\x1f\x8b", "gzip"),
    (b"MATLAB", "matlab"), (b"%PDF", "pdf"),
)
_UFF_START = re.compile(rb"\s*-1[ \t]*(\r|\n|$)")
_TEXT_CONTROLS = set(b"\t\n\r\f\v")


def read_head(path: Path, size: int = HEAD_BYTES) -> bytes:
    """The first ``size`` bytes of ``path`` (fewer for a shorter file)."""
    with path.open("rb") as handle:
        return handle.read(size)


def file_kind(head: bytes) -> str:
    """The kind of a file from its first bytes: a key of :data:`KIND_NAMES`.

    HDF5 files may start with a user block, so their signature is also looked for at
    offsets 512, 1024 and 2048 [bytes]. Text is told from binary data by the share of
    control characters and, for text that is not UTF-8, of bytes above 127.
    """
    if not head:
        return "empty"
    if any(head[offset:offset + 8] == _HDF5_SIGNATURE for offset in (0, 512, 1024, 2048)):
        return "hdf5"
    for signature, kind in _SIGNATURES:
        if head.startswith(signature):
            return kind
    if _UFF_START.match(head):
        return "uff"
    return "text" if looks_like_text(head) else "binary"


def looks_like_text(head: bytes) -> bool:
    """Whether ``head`` reads as text: UTF-8, UTF-16 (with or without a byte-order mark),
    or an 8-bit code page such as Latin-1 with few bytes above 127."""
    codec = None
    for mark, name in ((codecs.BOM_UTF16_LE, "utf-16-le"), (codecs.BOM_UTF16_BE, "utf-16-be")):
        if head.startswith(mark):
            head, codec = head[len(mark):], name
    if head.startswith(codecs.BOM_UTF8):
        head = head[len(codecs.BOM_UTF8):]
    codec = codec or unmarked_utf16(head)
    if codec:
        try:
            text = codecs.getincrementaldecoder(codec)().decode(head, final=False)
        except UnicodeDecodeError:
            return False
        return not any(ord(c) < 32 and ord(c) not in _TEXT_CONTROLS for c in text)
    if b"\x00" in head:
        return False
    controls = sum(1 for byte in head if (byte < 32 and byte not in _TEXT_CONTROLS) or byte == 127)
    if controls > 0.01 * len(head):
        return False
    try:
        codecs.getincrementaldecoder("utf-8")().decode(head, final=False)
    except UnicodeDecodeError:
        return sum(1 for byte in head if byte > 127) <= 0.1 * len(head)
    return True


def unmarked_utf16(head: bytes) -> str | None:
    """The codec of UTF-16 text without a byte-order mark (``"utf-16-le"`` or
    ``"utf-16-be"``), recognised by a NUL byte beside every ASCII character; else None."""
    even = head[:len(head) // 2 * 2]
    if len(even) < 8:
        return None
    for codec, zeros, letters in (("utf-16-le", even[1::2], even[0::2]), ("utf-16-be", even[0::2], even[1::2])):
        if zeros.count(0) == len(zeros) and letters.count(0) == 0:
            return codec
    return None


def one_line(message: object, limit: int = 240) -> str:
    """``message`` as one line of at most ``limit`` characters (for messages that quote
    a library's exception text)."""
    text = " ".join(str(message).split())
    return text if len(text) <= limit else text[:limit - 3] + "..."
