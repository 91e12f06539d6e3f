// SPDX-License-Identifier: MIT
// The viewer pages' colours and legend (tools/web/viewer/palette.js), under node's own test
// runner: `node --test tests/web/palette_test.mjs` (ctest runs it, label browser).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { PALETTE, acquisitionColours, legendHtml } from '../../tools/web/viewer/palette.js';

const BLUE = [59, 82, 139];     // the date ramp's oldest end
const YELLOW = [253, 231, 37];  // its newest end

// Frames of one drive, as citymesh writes their dates: whole seconds lose their fraction.
const frames = [
  { name: 'f0', date: '2026-01-01T00:00:00Z' },
  { name: 'f1', date: '2026-01-01T00:00:00.100Z' },
  { name: 'f2', date: '2026-01-01T00:00:00.200Z' },
];

test('by date, the oldest pass is blue and the newest yellow, by time and not by the strings', () => {
  const colours = acquisitionColours(frames, 'date');
  assert.deepEqual(colours[0], BLUE);
  assert.deepEqual(colours[2], YELLOW);
  assert.notDeepEqual(colours[1], BLUE);
  assert.notDeepEqual(colours[1], YELLOW);
});

test('by date, the colours follow the dates whatever the listing order; equal dates share one', () => {
  const months = ['2026-03-01T00:00:00Z', '2026-01-01T00:00:00Z', '2026-02-01T00:00:00Z', '2026-01-01T00:00:00Z'];
  const colours = acquisitionColours(months.map((date, k) => ({ name: `p${k}`, date })), 'date');
  assert.deepEqual(colours[1], BLUE);
  assert.deepEqual(colours[3], BLUE);
  assert.deepEqual(colours[0], YELLOW);
  assert.deepEqual(colours[2], acquisitionColours([frames[0], frames[1], frames[2]], 'date')[1]);
});

test('otherwise the palette by acquisition index, as citymesh pictures', () => {
  const colours = acquisitionColours(frames, undefined);
  assert.deepEqual(colours, [PALETTE[0], PALETTE[1], PALETTE[2]]);
});

test('the legend names each pass with its day, or its whole date when passes share a day', () => {
  const text = (html) => html.replace(/<[^>]*>/g, '');
  const days = [{ name: 'january', date: '2026-01-05T10:00:00Z' }, { name: 'march', date: '2026-03-02T09:00:00Z' }];
  assert.equal(text(legendHtml(days, acquisitionColours(days))), 'january (2026-01-05)march (2026-03-02)stitch');
  assert.equal(text(legendHtml(frames, acquisitionColours(frames))),
    'f0 (2026-01-01T00:00:00Z)f1 (2026-01-01T00:00:00.100Z)f2 (2026-01-01T00:00:00.200Z)stitch');
});
