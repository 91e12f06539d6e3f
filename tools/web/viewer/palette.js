// SPDX-License-Identifier: MIT
// The colours of the source acquisitions, shared by both viewer pages: by acquisition, the
// palette of citymesh's pictures (src/app/mosaic_output.cpp source_color); by date, a ramp
// from the oldest pass (blue) to the newest (yellow). Stitch triangles are magenta.
export const PALETTE = [[31, 119, 180], [255, 127, 14], [44, 160, 44], [214, 39, 40], [140, 86, 75],
  [23, 190, 207], [188, 189, 34], [127, 127, 127], [148, 103, 189], [0, 80, 40]];
export const STITCH = [230, 0, 230];
/// The feature id of stitch triangles (EXT_mesh_features nullFeatureId).
export const NULL_FEATURE = 65535;

// Viridis from its blue on (its purple end would read as the stitch magenta once shaded):
// ordered in lightness, so the ramp reads as old to new in grey too.
const RAMP = [[59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];

function rampAt(t) {
  const x = Math.min(Math.max(t, 0), 1) * (RAMP.length - 1);
  const i = Math.min(Math.floor(x), RAMP.length - 2), f = x - i;
  return RAMP[i].map((c, k) => Math.round(c + f * (RAMP[i + 1][k] - c)));
}

/// Milliseconds since 1970 of an ISO 8601 date as citymesh writes it. Not the string's order:
/// "…00:00:00.100Z" sorts before "…00:00:00Z".
const timeOf = (date) => Date.parse(date);

/// Per acquisition (feature id), its colour: `mode` 'date' ranks the distinct dates of
/// `acquisitions` ([{name, date}], ISO 8601, from the tiles' property table) oldest first;
/// otherwise the palette by id.
export function acquisitionColours(acquisitions, mode) {
  if (mode !== 'date') return acquisitions.map((_, id) => PALETTE[id % PALETTE.length]);
  const times = [...new Set(acquisitions.map((a) => timeOf(a.date)))].sort((x, y) => x - y);
  const rank = (a) => times.indexOf(timeOf(a.date));
  return acquisitions.map((a) => rampAt(times.length > 1 ? rank(a) / (times.length - 1) : 1));
}

/// The legend's HTML: each acquisition with its name and day (its whole date when passes
/// share a day, as frames of one drive do), then the stitch colour.
export function legendHtml(acquisitions, colours) {
  const days = new Set(acquisitions.map((a) => a.date.slice(0, 10)));
  const when = (a) => (days.size < acquisitions.length ? a.date : a.date.slice(0, 10));
  const swatch = (rgb) => `<span style="background: rgb(${rgb.join(',')})"></span>`;
  return acquisitions.map((a, id) => `${swatch(colours[id])}${a.name} (${when(a)})`).join('') +
    `${swatch(STITCH)}stitch`;
}

/// What a click on a triangle of feature `id` tells: its acquisition's name, date and index,
/// or that citymesh's stitching made it.
export function describePick(acquisitions, id) {
  if (id === NULL_FEATURE) return 'a stitch triangle (made by citymesh between two passes)';
  const a = acquisitions[id];
  return a ? `${a.name}, ${a.date} (acquisition ${id})` : `acquisition ${id}`;
}
