"""Imports: files GDAL wrote from the shared GeoJSON plan exactly as the GeoJSON does."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import shapely
from shapely import MultiPolygon, Polygon

from planner import CoveragePlan, plan_coverage
from planner.errors import FieldChoiceError, InvalidFieldError, UnreadableFileError
from planner.fields import FieldSpec
from planner.io import fields_to_geojson, read_fields, select_field
from tests.conftest import FIELDS_DIR, PAPER_FIELD
from tests.planner.field_files import (
    REAL_FIELDS,
    google_earth_kmz_bytes,
    gpkg_bytes,
    kml_bytes,
    kmz_bytes,
    shared_feature,
    shared_polygon,
    zipped_utm_shapefile_bytes,
)

MAKERS = {
    "kml": kml_bytes,
    "kmz-gdal": kmz_bytes,
    "kmz-google-earth": google_earth_kmz_bytes,
    "shapefile-utm-zip": zipped_utm_shapefile_bytes,
}


def plan_of(spec: FieldSpec) -> CoveragePlan:
    return plan_coverage(spec.field_lonlat, interval_m=4.0)


def assert_same_plan(a: CoveragePlan, b: CoveragePlan) -> None:
    assert a.stats.line_count == b.stats.line_count
    assert a.stats.waypoint_count == b.stats.waypoint_count
    assert a.stats.angle_deg == pytest.approx(b.stats.angle_deg, abs=1e-6)
    for wa, wb in zip(a.waypoints, b.waypoints, strict=True):
        assert (wa.role, wa.line) == (wb.role, wb.line)
        # 1e-7° is about 1 cm: a UTM round trip moves vertices by far less.
        assert wa.lon == pytest.approx(wb.lon, abs=1e-7)
        assert wa.lat == pytest.approx(wb.lat, abs=1e-7)


@pytest.mark.parametrize("field", ["paper", "rwanda-3", "germany-22-hole"])
@pytest.mark.parametrize("fmt", list(MAKERS))
def test_import_plans_as_the_geojson_does(field: str, fmt: str, tmp_path: Path) -> None:
    path, feature_id = REAL_FIELDS[field]
    geojson = shared_feature(path, feature_id)
    reference = read_fields(json.dumps(geojson).encode(), filename="f.geojson")
    assert len(reference) == 1
    polygon = shared_polygon(field)
    data = MAKERS[fmt](tmp_path, polygon)
    fields = read_fields(data, filename=f"field.{fmt}")
    assert len(fields) == 1
    imported = fields[0].field_lonlat
    assert len(imported.interiors) == len(polygon.interiors)
    assert imported.symmetric_difference(polygon).area < 1e-6 * polygon.area
    assert_same_plan(plan_of(fields[0]), plan_of(reference[0]))


def test_geopackage_of_several_fields_in_web_mercator_lists_them_all(tmp_path: Path) -> None:
    collection = json.loads((FIELDS_DIR / "rwanda_2021.geojson").read_text())
    polygons = [shapely.from_geojson(json.dumps(f["geometry"])) for f in collection["features"]]
    names = [f["properties"]["id"] for f in collection["features"]]
    data = gpkg_bytes(tmp_path, polygons, names, crs="EPSG:3857")
    fields = read_fields(data, filename="rwanda.gpkg")
    assert [f.name for f in fields] == names
    reference = read_fields((FIELDS_DIR / "rwanda_2021.geojson").read_bytes(), filename="r.geojson")
    chosen = select_field(fields, "rwanda_2021-3", filename="rwanda.gpkg")
    assert chosen is fields[3]
    assert_same_plan(plan_of(chosen), plan_of(reference[3]))


def test_thirty_field_geojson_lists_thirty_with_id_name_and_area() -> None:
    fields = read_fields((FIELDS_DIR / "rwanda_2021.geojson").read_bytes(), filename="r.geojson")
    listing = fields_to_geojson(fields)
    assert len(listing["features"]) == 30
    collection = json.loads((FIELDS_DIR / "rwanda_2021.geojson").read_text())
    for feature, source in zip(listing["features"], collection["features"], strict=True):
        props = feature["properties"]
        assert props["id"] == source["properties"]["id"]
        # The shared files' area_m2 is geodesic too (README).
        assert props["area_m2"] == pytest.approx(source["properties"]["area_m2"], rel=1e-4)


def test_select_field_by_id_name_and_index_and_refuses_none_of_many() -> None:
    fields = read_fields((FIELDS_DIR / "rwanda_2021.geojson").read_bytes(), filename="r.geojson")
    assert select_field(fields, "3", filename="r") is fields[3]
    assert select_field(fields, "rwanda_2021-7", filename="r") is fields[7]
    with pytest.raises(FieldChoiceError, match="holds 30 fields") as none:
        select_field(fields, None, filename="r.geojson")
    assert len(none.value.choices) == 30
    with pytest.raises(FieldChoiceError, match="index from 0 to 29"):
        select_field(fields, "30", filename="r.geojson")


def test_multipolygon_parts_are_several_fields(tmp_path: Path) -> None:
    a, b = shared_polygon("paper"), shared_polygon("rwanda-3")
    feature = {
        "type": "Feature",
        "properties": {"id": "farm", "name": "Farm"},
        "geometry": json.loads(shapely.to_geojson(MultiPolygon([a, b]))),
    }
    fields = read_fields(json.dumps(feature).encode(), filename="farm.geojson")
    assert [f.feature_id for f in fields] == ["farm.1", "farm.2"]
    assert [f.name for f in fields] == ["Farm (1 of 2)", "Farm (2 of 2)"]
    assert fields[1].field_lonlat.equals(b)


def test_paper_file_keeps_start_finish_and_interval() -> None:
    (spec,) = read_fields(PAPER_FIELD.read_bytes(), filename="paper.geojson")
    collection = json.loads(PAPER_FIELD.read_text())
    points = {f["properties"]["role"]: f["geometry"]["coordinates"] for f in collection["features"]}
    assert spec.start_lonlat == tuple(points["start"])
    assert spec.finish_lonlat == tuple(points["finish"])
    assert spec.interval_m == 4.0


def test_shapefile_without_prj_is_refused_naming_the_prj(tmp_path: Path) -> None:
    import io
    import zipfile

    data = zipped_utm_shapefile_bytes(tmp_path, shared_polygon("paper"))
    source = zipfile.ZipFile(io.BytesIO(data))
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for info in source.infolist():
            if not info.filename.endswith(".prj"):
                archive.writestr(info.filename, source.read(info))
    with pytest.raises(UnreadableFileError, match=r"field\.zip: .*no \.prj"):
        read_fields(buffer.getvalue(), filename="field.zip")


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (bytes(range(256)) * 4, "is binary data tillpath cannot read"),
        (b"\x7fELF\x02\x01\x01\x00" + b"\x00" * 64, "is binary data"),
        (b"", "is empty"),
        (b"lon,lat\n1,2\n", "neither JSON nor XML"),
        (b'{"type": "Polygon", ', "is not valid JSON"),
        (b"\xff\xfe{\x00", "binary"),
        (b"PK\x03\x04not really a zip", "is not a readable zip archive"),
        (b"<kml><Document></kml>", "is not well-formed XML"),
    ],
)
def test_unreadable_files_get_a_clear_error_naming_the_file(data: bytes, message: str) -> None:
    with pytest.raises(UnreadableFileError, match=message) as error:
        read_fields(data, filename="upload.bin")
    assert str(error.value).startswith("upload.bin: ")


def test_a_zip_of_neither_shapefile_nor_kml_is_refused() -> None:
    import io
    import zipfile

    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr("word/document.xml", "<w/>")
    with pytest.raises(UnreadableFileError, match="neither a Shapefile"):
        read_fields(buffer.getvalue(), filename="letter.docx")


def test_kml_without_polygon_is_an_invalid_field(tmp_path: Path) -> None:
    kml = (
        b'<?xml version="1.0"?><kml xmlns="http://www.opengis.net/kml/2.2"><Document>'
        b"<Placemark><name>gate</name><Point><coordinates>115.3,-8.6</coordinates></Point>"
        b"</Placemark></Document></kml>"
    )
    with pytest.raises(InvalidFieldError, match="gate.kml: holds no field boundary"):
        read_fields(kml, filename="gate.kml")


def test_kml_start_and_finish_placemarks_are_the_gates(tmp_path: Path) -> None:
    polygon = shared_polygon("paper")
    kml = kml_bytes(tmp_path, polygon).decode()
    gates = (
        "<Placemark><name>start</name><Point><coordinates>115.29797264,-8.62652248"
        "</coordinates></Point></Placemark>"
        "<Placemark><name>Finish</name><Point><coordinates>115.29816889,-8.62652064"
        "</coordinates></Point></Placemark></Document>"
    )
    (spec,) = read_fields(kml.replace("</Document>", gates).encode(), filename="f.kml")
    assert spec.start_lonlat == pytest.approx((115.29797264, -8.62652248))
    assert spec.finish_lonlat == pytest.approx((115.29816889, -8.62652064))
    assert isinstance(spec.field_lonlat, Polygon)


def test_google_earth_layout_with_style_maps_folders_and_altitudes_reads(tmp_path: Path) -> None:
    """The layout Google Earth Pro saves (namespaces, StyleMap, nested Folder, lon,lat,0 text).

    GDAL writes no such file, so the layout is spelled out here; the coordinates are the shared
    paper field's.
    """
    polygon = shared_polygon("paper")
    coords = " ".join(f"{x},{y},0" for x, y in polygon.exterior.coords)
    kml = f"""<?xml version="1.0" encoding="UTF-8"?>
<kml xmlns="http://www.opengis.net/kml/2.2" xmlns:gx="http://www.google.com/kml/ext/2.2"
 xmlns:kml="http://www.opengis.net/kml/2.2" xmlns:atom="http://www.w3.org/2005/Atom">
<Document>
	<name>Sawah Ketewel.kml</name>
	<StyleMap id="m_ylw-pushpin"><Pair><key>normal</key><styleUrl>#s_ylw-pushpin</styleUrl></Pair>
		<Pair><key>highlight</key><styleUrl>#s_ylw-pushpin_hl</styleUrl></Pair></StyleMap>
	<Style id="s_ylw-pushpin"><LineStyle><color>ff00ffff</color></LineStyle></Style>
	<Folder><name>My Places</name><open>1</open>
	<Placemark>
		<name>Sawah Ketewel</name>
		<styleUrl>#m_ylw-pushpin</styleUrl>
		<Polygon>
			<tessellate>1</tessellate>
			<outerBoundaryIs>
				<LinearRing>
					<coordinates>
						{coords}
					</coordinates>
				</LinearRing>
			</outerBoundaryIs>
		</Polygon>
	</Placemark>
	</Folder>
</Document>
</kml>
"""
    (spec,) = read_fields(kml.encode(), filename="Sawah Ketewel.kml")
    assert spec.name == "Sawah Ketewel"
    assert spec.field_lonlat.equals(polygon)
    # The same plan as the paper field's own polygon (whatever heading the search keeps).
    assert_same_plan(plan_of(spec), plan_coverage(polygon, interval_m=4.0))


def test_kml_multigeometry_of_two_polygons_is_two_fields() -> None:
    a, b = shared_polygon("paper"), shared_polygon("rwanda-3")

    def ring(p: Polygon) -> str:
        coords = " ".join(f"{x},{y},0" for x, y in p.exterior.coords)
        return (
            f"<Polygon><outerBoundaryIs><LinearRing><coordinates>{coords}</coordinates>"
            "</LinearRing></outerBoundaryIs></Polygon>"
        )

    kml = (
        '<kml xmlns="http://www.opengis.net/kml/2.2"><Document><Placemark><name>Farm</name>'
        f"<MultiGeometry>{ring(a)}{ring(b)}</MultiGeometry></Placemark></Document></kml>"
    )
    fields = read_fields(kml.encode(), filename="farm.kml")
    assert [f.name for f in fields] == ["Farm (1 of 2)", "Farm (2 of 2)"]
    assert fields[0].field_lonlat.equals(a) and fields[1].field_lonlat.equals(b)
