// SPDX-License-Identifier: MIT
// The colours of the source acquisitions, shared by both viewer pages: the palette of
// citymesh's pictures (src/app/mosaic_output.cpp source_color), stitch triangles magenta.
export const PALETTE = [[31, 119, 180], [255, 127, 14], [44, 160, 44], [214, 39, 40], [140, 86, 75],
  [23, 190, 207], [188, 189, 34], [127, 127, 127], [148, 103, 189], [0, 80, 40]];
export const STITCH = [230, 0, 230];
/// The feature id of stitch triangles (EXT_mesh_features nullFeatureId).
export const NULL_FEATURE = 65535;

/// The legend's HTML for the acquisitions seen so far, then the stitch colour.
export function legendHtml(seen) {
  return [...seen].sort((a, b) => a - b)
    .map((id) => `<span style="background: rgb(${PALETTE[id % PALETTE.length].join(',')})"></span>acquisition ${id}`)
    .join('') + `<span style="background: rgb(${STITCH.join(',')})"></span>stitch`;
}
