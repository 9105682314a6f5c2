"""Archive and XML safety: the one place an uploaded file is checked before anything parses it.

- **Archives** (KMZ, zipped Shapefiles): the zip's directory is read first and the archive is
  refused, before one byte is inflated, when it has too many members, its members would
  inflate past a total size, or it inflates more than a ratio times its own size (zip bombs).
  Inflating then stops at each member's declared size, so a directory that lies cannot make a
  member larger. Encrypted members are refused. Nothing is written to disk.
- **XML** (KML, GPX): parsed once with defusedxml with DTDs, entity declarations and
  external references forbidden, so the "billion laughs" bomb and XXE are refused at their
  first declaration, before any entity is expanded.
"""

from __future__ import annotations

import io
import zipfile
from dataclasses import dataclass
from typing import Final

import defusedxml.ElementTree
from defusedxml import DefusedXmlException

from planner.errors import UnreadableFileError


@dataclass(frozen=True, slots=True)
class ArchiveLimits:
    """How large an archive may inflate.

    Attributes
    ----------
    max_members : int
        Entries in the zip directory.
    max_total_bytes : int
        Sum of the members' uncompressed sizes [bytes].
    max_ratio : float
        Uncompressed total over the archive's own size. Text compresses ~5–20 times; bombs
        compress a thousand times and more.
    """

    max_members: int = 512
    max_total_bytes: int = 64 * 1024 * 1024
    max_ratio: float = 200.0


DEFAULT_LIMITS: Final = ArchiveLimits()

ZIP_MAGIC: Final = b"PK\x03\x04"


def unzip_checked(
    data: bytes, *, filename: str, limits: ArchiveLimits = DEFAULT_LIMITS
) -> dict[str, bytes]:
    """Return the members of zip archive ``data`` by name, after checking its sizes.

    Parameters
    ----------
    data : bytes
        The archive.
    filename : str
        Named in errors.
    limits : ArchiveLimits

    Returns
    -------
    dict of str to bytes
        Member name -> contents, directories left out.

    Raises
    ------
    UnreadableFileError
        If ``data`` is not a zip archive, is over a limit, holds encrypted members or is
        corrupt.

    Examples
    --------
    >>> buffer = io.BytesIO()
    >>> with zipfile.ZipFile(buffer, "w") as archive:
    ...     archive.writestr("doc.kml", "<kml/>")
    >>> unzip_checked(buffer.getvalue(), filename="a.kmz")
    {'doc.kml': b'<kml/>'}
    """
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
    except (zipfile.BadZipFile, ValueError, OSError) as exc:
        raise UnreadableFileError(filename, f"is not a readable zip archive ({exc})") from None
    with archive:
        infos = [info for info in archive.infolist() if not info.is_dir()]
        if len(infos) > limits.max_members:
            raise UnreadableFileError(
                filename,
                f"the archive holds {len(infos)} files, more than the {limits.max_members} allowed",
            )
        total = sum(info.file_size for info in infos)
        if total > limits.max_total_bytes:
            raise UnreadableFileError(
                filename,
                f"the archive would unpack to {total:,} bytes, more than the "
                f"{limits.max_total_bytes:,} allowed",
            )
        if total > limits.max_ratio * max(len(data), 1):
            raise UnreadableFileError(
                filename,
                f"the archive would unpack to {total / max(len(data), 1):,.0f} times its size "
                f"(at most {limits.max_ratio:,.0f}); it looks like a zip bomb",
            )
        members: dict[str, bytes] = {}
        for info in infos:
            if info.flag_bits & 0x1:
                raise UnreadableFileError(filename, f"{info.filename} is encrypted")
            try:
                with archive.open(info) as member:
                    # ZipExtFile never returns more than the declared size (checked above).
                    members[info.filename] = member.read(info.file_size + 1)
            except (zipfile.BadZipFile, NotImplementedError, ValueError, OSError, EOFError) as exc:
                raise UnreadableFileError(
                    filename, f"{info.filename} cannot be unpacked ({exc})"
                ) from None
            except RuntimeError as exc:  # zipfile: "File is encrypted, password required"
                raise UnreadableFileError(filename, f"{info.filename}: {exc}") from None
        return members


def check_xml(data: bytes, *, filename: str, kind: str) -> None:
    """Refuse XML with a DTD, entity declarations or external references, or malformed XML.

    Parameters
    ----------
    data : bytes
        The document.
    filename : str
        Named in errors.
    kind : str
        What the document should be (``KML``, ``GPX``), named in errors.

    Raises
    ------
    UnreadableFileError
        If the document declares a DTD or entities (XXE, billion laughs) or is not
        well-formed.

    Examples
    --------
    >>> check_xml(b"<kml><Document/></kml>", filename="a.kml", kind="KML")
    >>> bomb = b'<!DOCTYPE k [<!ENTITY a "aaaa">]><kml>&a;</kml>'
    >>> check_xml(bomb, filename="a.kml", kind="KML")
    Traceback (most recent call last):
    ...
    planner.errors.UnreadableFileError: a.kml: KML with a DTD, entity declarations or \
external references is refused
    """
    try:
        defusedxml.ElementTree.fromstring(
            data, forbid_dtd=True, forbid_entities=True, forbid_external=True
        )
    except DefusedXmlException:
        raise UnreadableFileError(
            filename, f"{kind} with a DTD, entity declarations or external references is refused"
        ) from None
    except Exception as exc:  # ParseError: not well-formed (truncated, binary, …)
        raise UnreadableFileError(filename, f"is not well-formed XML ({exc})") from None
