// Reading a field from a GeoJSON file, the same convention as `tillpath plan FIELD`
// (product.md §10): the field is the polygon, Points with properties.role "start"/"finish" are
// the start and finish, and an `interval_m` property sets the interval. Only reading happens
// here; checking the polygon is the planner's job, so the API's error names any problem.

import { t } from "./i18n.js";

/** A file that cannot be used as a field; `message` is meant for the person who chose it. */
export class FieldFileError extends Error {}

function featuresOf(data) {
  if (data?.type === "FeatureCollection" && Array.isArray(data.features)) return data.features;
  if (data?.type === "Feature") return [data];
  if (typeof data?.type === "string" && "coordinates" in data) {
    return [{ type: "Feature", properties: {}, geometry: data }];
  }
  throw new FieldFileError(t("Import field: this file is not GeoJSON (no features or geometry found)."));
}

/** The first polygon; a MultiPolygon of exactly one polygon counts as that polygon. */
function findPolygon(features) {
  for (const feature of features) {
    const geometry = feature?.geometry;
    if (geometry?.type === "Polygon") return { feature, polygon: geometry };
    if (geometry?.type === "MultiPolygon" && geometry.coordinates?.length === 1) {
      return { feature, polygon: { type: "Polygon", coordinates: geometry.coordinates[0] } };
    }
  }
  throw new FieldFileError(
    t("Import field: the file has no field boundary (a Polygon). Draw the field instead, or export it as GeoJSON polygon."),
  );
}

function findPoint(features, role) {
  const feature = features.find(
    (f) => f?.geometry?.type === "Point" && f.properties?.role === role,
  );
  const coordinates = feature?.geometry?.coordinates;
  return Array.isArray(coordinates) ? [Number(coordinates[0]), Number(coordinates[1])] : null;
}

/** Reject projected coordinates early: the API would only say the field is far away. */
function checkLonLat(polygon) {
  const ring = polygon.coordinates?.[0];
  if (!Array.isArray(ring) || ring.length < 4) {
    throw new FieldFileError(t("Import field: the boundary needs at least three corners."));
  }
  const outside = ring.some(
    ([lon, lat]) => !(Math.abs(lon) <= 180 && Math.abs(lat) <= 90),
  );
  if (outside) {
    throw new FieldFileError(
      t("Import field: the coordinates are not longitude and latitude (WGS84). Save the file as GeoJSON in EPSG:4326."),
    );
  }
}

/**
 * The field polygon of any GeoJSON object (Polygon, Feature or FeatureCollection), as stored in
 * a plan's request.
 *
 * @throws {FieldFileError} When there is no polygon.
 */
export function polygonOf(data) {
  return findPolygon(featuresOf(data)).polygon;
}

/**
 * Read a field file's text.
 *
 * @param {string} text The file's contents.
 * @returns {{field: object, start: number[]|null, finish: number[]|null,
 *            intervalM: number|null, name: string|null}}
 * @throws {FieldFileError} When the text is not GeoJSON or holds no usable polygon.
 */
export function readFieldFile(text) {
  let data;
  try {
    data = JSON.parse(text);
  } catch {
    throw new FieldFileError(t("Import field: this file is not GeoJSON (it is not valid JSON)."));
  }
  const features = featuresOf(data);
  const { feature, polygon } = findPolygon(features);
  checkLonLat(polygon);
  const interval = Number(
    feature.properties?.interval_m ??
      data.properties?.interval_m ??
      features.find((f) => f?.properties?.interval_m != null)?.properties.interval_m,
  );
  const name = feature.properties?.name ?? data.name ?? null;
  return {
    field: polygon,
    start: findPoint(features, "start"),
    finish: findPoint(features, "finish"),
    intervalM: Number.isFinite(interval) && interval > 0 ? interval : null,
    name: typeof name === "string" ? name : null,
  };
}
