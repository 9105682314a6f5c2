"""What the map page draws for a small tractor on a real field: the turns read back from the
Leaflet layers on the page (not from the API's answer), each buffered by half the tractor's
width, lie inside the field (issue 9, R1)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import shapely
from playwright.sync_api import Page, expect
from shapely.geometry import LineString, shape

from planner.projection import field_frame
from tests.browser.conftest import SHARED
from tests.browser.test_map_page import button, generate

pytestmark = pytest.mark.browser

#: A real, non-convex 0.9 ha field of the Rwandan dataset (README of ../shared/fields).
REAL_FIELD = ("rwanda_2021", "rwanda_2021-1")

#: Keeps every Leaflet map the page makes, so the test can read its layers back.
CAPTURE_MAPS = """
(() => {
  const maps = [];
  let leaflet;
  window.__tillpathMaps = maps;
  Object.defineProperty(window, "L", {
    configurable: true,
    get: () => leaflet,
    set: (value) => {
      leaflet = value;
      value?.Map?.addInitHook?.(function () { maps.push(this); });
    },
  });
})();
"""

#: The drawn plan features: every Leaflet layer made from a GeoJSON feature, with its kind.
DRAWN = """
() => {
  const out = [];
  const flat = (latlngs) => latlngs.flat(Infinity).map((p) => [p.lng, p.lat]);
  for (const map of window.__tillpathMaps) {
    map.eachLayer((layer) => {
      const kind = layer.feature?.properties?.kind;
      if (kind && layer.getLatLngs) out.push({ kind, coordinates: flat(layer.getLatLngs()) });
    });
  }
  return out;
}
"""


def write_real_field(tmp_path: Path) -> Path:
    dataset, field_id = REAL_FIELD
    collection = json.loads((SHARED / "fields" / f"{dataset}.geojson").read_text())
    feature = next(f for f in collection["features"] if f["properties"]["id"] == field_id)
    path = tmp_path / f"{field_id}.geojson"
    path.write_text(json.dumps({"type": "FeatureCollection", "features": [feature]}))
    return path


@pytest.mark.parametrize("pattern", ["boustrophedon", "spiral"])
def test_drawn_small_tractor_turns_stay_inside_a_real_field(
    page: Page, tmp_path: Path, pattern: str
) -> None:
    page.add_init_script(CAPTURE_MAPS)
    page.reload()
    expect(page.locator("#app")).to_have_attribute("data-ready", "true")
    with page.expect_file_chooser() as chooser:
        button(page, "Import field").click()
    chooser.value.set_files(write_real_field(tmp_path))
    page.wait_for_function(  # the imported field is on the map (its editable polygon)
        "() => window.__tillpathMaps.some((m) => { let found = false; m.eachLayer((l) => {"
        " if (l instanceof L.Polygon && !l.feature) found = true; }); return found; })"
    )
    page.get_by_label("Vehicle", exact=True).select_option("small_tractor")
    page.get_by_label("Pattern", exact=True).select_option(pattern)
    page.get_by_label("Interval (m)").fill("4")

    plan = generate(page)

    assert plan["request"]["vehicle"] == "small_tractor"
    answered = [f for f in plan["geojson"]["features"] if f["properties"]["kind"] == "turn"]
    assert answered, "a plan of this field has turns"
    page.wait_for_function(
        "(n) => window.__tillpathMaps.some((m) => { let k = 0; m.eachLayer((l) => {"
        " if (l.feature?.properties?.kind === 'turn') k += 1; }); return k === n; })",
        arg=len(answered),
    )
    drawn = page.evaluate(DRAWN)
    turns = [d["coordinates"] for d in drawn if d["kind"] == "turn"]
    assert len(turns) == len(answered)
    field_lonlat = shape(plan["request"]["field"])  # the field the page drew and sent
    frame = field_frame(field_lonlat)
    inside = frame.to_local(field_lonlat).buffer(0.01)
    half = plan["stats"]["vehicle"]["width_m"] / 2
    for coordinates in turns:
        body = frame.to_local(LineString(coordinates)).buffer(half)
        outside = shapely.difference(body, inside).area
        assert outside < 1e-6, f"a drawn turn's body leaves the field by {outside:.4f} m²"
    if pattern == "spiral":
        assert any(d["kind"] == "round" for d in drawn), "the spiral's rounds are drawn"
