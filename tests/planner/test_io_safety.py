"""Hostile files are refused fast: zip bombs before inflating, XML bombs and XXE at once."""

from __future__ import annotations

import io
import time
import zipfile

import pytest

from planner.errors import UnreadableFileError
from planner.io import ArchiveLimits, read_fields, unzip_checked

BILLION_LAUGHS = (
    b'<?xml version="1.0"?>\n<!DOCTYPE lolz [\n <!ENTITY lol "lol">\n'
    + b"".join(
        f' <!ENTITY lol{i} "{("&lol" + (str(i - 1) if i > 1 else "") + ";") * 10}">\n'.encode()
        for i in range(1, 10)
    )
    + b']>\n<kml xmlns="http://www.opengis.net/kml/2.2"><Document><name>&lol9;</name>'
    b"</Document></kml>"
)
XXE = (
    b'<?xml version="1.0"?><!DOCTYPE kml [<!ENTITY xxe SYSTEM "file:///etc/passwd">]>'
    b'<kml xmlns="http://www.opengis.net/kml/2.2"><Document><name>&xxe;</name></Document></kml>'
)


def zipped(members: dict[str, bytes]) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return buffer.getvalue()


@pytest.mark.parametrize(("xml", "name"), [(BILLION_LAUGHS, "lol.kml"), (XXE, "xxe.kml")])
def test_xml_bombs_and_external_entities_are_refused_fast(xml: bytes, name: str) -> None:
    started = time.perf_counter()
    with pytest.raises(UnreadableFileError, match="DTD, entity declarations"):
        read_fields(xml, filename=name)
    assert time.perf_counter() - started < 0.5


def test_billion_laughs_inside_a_kmz_is_refused() -> None:
    with pytest.raises(UnreadableFileError, match=r"bomb\.kmz/doc\.kml: KML with a DTD"):
        read_fields(zipped({"doc.kml": BILLION_LAUGHS}), filename="bomb.kmz")


def test_zip_bomb_is_refused_by_its_ratio_before_inflating() -> None:
    bomb = zipped({"field.shp": bytes(20_000_000)})  # 20 MB of zeros: ~20 kB zipped
    assert len(bomb) < 100_000
    started = time.perf_counter()
    with pytest.raises(UnreadableFileError, match="zip bomb"):
        read_fields(bomb, filename="bomb.zip")
    # Inflating 20 MB would take longer than this; the directory alone is read.
    assert time.perf_counter() - started < 0.05


def test_archive_over_the_total_size_is_refused() -> None:
    data = zipped({"a.kml": bytes(range(256)) * 8_000})  # 2 MB that barely compresses
    limits = ArchiveLimits(max_total_bytes=1_000_000)
    with pytest.raises(UnreadableFileError, match="would unpack to 2,048,000 bytes"):
        unzip_checked(data, filename="big.kmz", limits=limits)


def test_archive_with_too_many_members_is_refused() -> None:
    data = zipped({f"f{i}.kml": b"" for i in range(600)})
    with pytest.raises(UnreadableFileError, match="600 files, more than the 512"):
        read_fields(data, filename="many.zip")


def test_member_larger_than_declared_is_refused() -> None:
    data = bytearray(zipped({"doc.kml": b"<kml>" + b" " * 5000 + b"</kml>"}))
    # Shrink the declared size in the central directory (a lying archive).
    central = data.rfind(b"PK\x01\x02")
    data[central + 24 : central + 28] = (10).to_bytes(4, "little")
    with pytest.raises(UnreadableFileError, match="doc.kml cannot be unpacked"):
        unzip_checked(bytes(data), filename="liar.kmz")


def test_kml_links_to_other_servers_are_not_fetched() -> None:
    """No request leaves for a NetworkLink, a remote style or an icon (no SSRF through GDAL)."""
    import http.server
    import threading

    requests: list[str] = []

    class Recorder(http.server.BaseHTTPRequestHandler):
        def do_GET(self) -> None:  # noqa: N802 - the http.server API
            requests.append(self.path)
            self.send_response(404)
            self.end_headers()

        def log_message(self, *args: object) -> None:
            pass

    server = http.server.HTTPServer(("127.0.0.1", 0), Recorder)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    base = f"http://127.0.0.1:{server.server_address[1]}"
    kml = f"""<?xml version="1.0" encoding="UTF-8"?>
<kml xmlns="http://www.opengis.net/kml/2.2"><Document>
<NetworkLink><name>more</name><Link><href>{base}/more.kml</href></Link></NetworkLink>
<Style id="s"><IconStyle><Icon><href>{base}/icon.png</href></Icon></IconStyle></Style>
<Placemark><name>f</name><styleUrl>{base}/styles.kml#s</styleUrl><Polygon><outerBoundaryIs>
<LinearRing><coordinates>115.298,-8.6265 115.2981,-8.6265 115.2981,-8.6264 115.298,-8.6265
</coordinates></LinearRing></outerBoundaryIs></Polygon></Placemark></Document></kml>"""
    try:
        (spec,) = read_fields(kml.encode(), filename="links.kml")
        kmz = zipped({"doc.kml": kml.encode()})
        read_fields(kmz, filename="links.kmz")
    finally:
        server.shutdown()
        server.server_close()
    assert spec.name == "f"
    assert requests == []
