// SPDX-License-Identifier: MIT
// Tile result files: the labels, consistent pairs and selected triangles of one finished tile.
#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <span>
#include <string_view>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/checksum.h"
#include "citymesh/core/log.h"
#include "citymesh/core/read_file.h"
#include "citymesh/core/varint.h"
#include "tile_job.h"

namespace citymesh::app {

namespace {

// Version 02: a version 01 result may have been cut short by a failing worker (fixed in
// parallel_workers); such folders are processed again rather than trusted.
// Version 03: the checksum is XXH3 (bulk_checksum) instead of FNV-1a.
// Version 04: each label carries the mosaic's notes (seen through, filled, left out by the
// fill) in what was padding; older results would read as "nothing noted".
// Version 05: labels and pairs as varint deltas (about 7 and 6 bytes instead of 32 and 16: the
// results of a city took more than the tile store); older results are processed again.
// Version 06: the change step's figures (ChangeFigures), which the detect summary of a tiled
// run sums; older results would leave it zeros.
// Version 07: the copies refuted by the tile's owned triangles (TileResult::refuted); older
// results counted refutes differently.
// Version 08: what the result was made from (the tile's inputs digest, the fingerprint of its
// neighbours' decisions on its halo) and whether it was kept that way, so that a result is
// kept when only a neighbour was redone, to the same decisions.
// Version 09: the acquisitions the tile held, by index (TileResult::passes), so that a result
// is renumbered rather than made again when a pass delivered late renumbers them. Older
// results are processed again (they were under the digest of another build anyway).
constexpr char kMagic[8] = {'C', 'M', 'R', 'S', 'L', 'T', '0', '9'};

/// ChangeStats as stored, in the order of kChangeCounts and kChangeSeconds.
struct ChangeFigures {
  std::array<std::uint64_t, kChangeCounts.size()> counts;
  std::array<double, kChangeSeconds.size()> seconds;
};
static_assert(sizeof(ChangeFigures) == 88);

ChangeFigures figures_of(const ChangeStats& s) {
  ChangeFigures f{};
  for (std::size_t k = 0; k < kChangeCounts.size(); ++k) f.counts[k] = s.*kChangeCounts[k];
  for (std::size_t k = 0; k < kChangeSeconds.size(); ++k) f.seconds[k] = s.*kChangeSeconds[k];
  return f;
}

ChangeStats stats_of(const ChangeFigures& f) {
  ChangeStats s;
  for (std::size_t k = 0; k < kChangeCounts.size(); ++k) s.*kChangeCounts[k] = f.counts[k];
  for (std::size_t k = 0; k < kChangeSeconds.size(); ++k) s.*kChangeSeconds[k] = f.seconds[k];
  return s;
}

struct ResultHeader {
  char magic[8];
  std::uint64_t fingerprint;  ///< the tile's digest (tile_digests)
  std::int32_t i, j;
  std::uint64_t labels, pairs, acquisitions, triangles_in_tile;
  double seconds_read, seconds_detect, seconds_mosaic;
  std::uint64_t label_bytes, pair_bytes;  ///< the two varint sections that follow the header
  ChangeFigures change;
  std::uint64_t refuted, refuted_bytes;                   ///< the third varint section, after the pairs
  std::uint64_t inputs_fingerprint, settled_fingerprint;  ///< ResultOrigin (version 08)
  std::uint64_t kept;                                     ///< 1 when last written by restamp_tile_result (version 08)
  std::uint64_t passes;  ///< the fourth section, after the refuted copies: 4 bytes each (version 09)
};
static_assert(sizeof(ResultHeader) == 232);

/// A label's state, flags and notes in one varint (state < 4, flags 0 or 1, notes 8 bits).
std::uint64_t label_bits(const OwnedLabel& l) {
  return static_cast<std::uint64_t>(l.state) | std::uint64_t{l.kept != 0} << 2 |
         std::uint64_t{l.sustainable != 0} << 3 | std::uint64_t{l.refutes != 0} << 4 |
         std::uint64_t{l.selected != 0} << 5 | std::uint64_t{l.notes} << 6;
}

/// Varints per label: acquisition, index, bits, first and last seen.
constexpr std::size_t kVarintsPerLabel = 5;
/// The fields of a record stored as varints, each a delta against the previous record's.
template <class Record, std::size_t N>
using DeltaFields = std::array<std::uint32_t Record::*, N>;
/// Varints per pair (LabelPairList): its four fields.
constexpr std::size_t kVarintsPerPair = 4;
constexpr DeltaFields<RefutedCopy, 2> kRefutedFields{&RefutedCopy::acquisition, &RefutedCopy::index};

/// Records (sorted: the deltas stay small) as deltas against the previous record.
template <class Record, std::size_t N>
VarintWriter encode_deltas(std::span<const Record> records, const DeltaFields<Record, N>& fields) {
  VarintWriter w(records.size() * N * max_varint_bytes(32));
  Record running{};
  for (const Record& r : records) {
    for (const auto field : fields) w.put_next(r.*field, running.*field);
  }
  return w;
}

/// The inverse of encode_deltas; false when the bytes do not hold `count` records.
template <class Record, std::size_t N>
bool decode_deltas(std::string_view bytes, std::size_t count, const DeltaFields<Record, N>& fields,
                   std::vector<Record>& records) {
  VarintReader in(bytes.data(), bytes.data() + bytes.size());
  records.resize(count);
  Record running{};
  for (Record& r : records) {
    for (const auto field : fields) {
      if (!in.get_next(running.*field)) return false;
    }
    r = running;
  }
  return in.at_end();
}

/// Labels (sorted by triangle) as deltas against the previous label: consecutive labels are
/// mostly the next triangle of the same acquisition, seen over the same dates.
VarintWriter encode_labels(std::span<const OwnedLabel> labels) {
  VarintWriter w(labels.size() * (kVarintsPerLabel - 1) * max_varint_bytes(64) + labels.size() * max_varint_bytes(14));
  std::uint32_t acquisition = 0, index = 0;
  std::uint64_t first = 0, last = 0;  // Unix milliseconds, as two's complement
  for (const OwnedLabel& l : labels) {
    w.put_next(l.acquisition, acquisition);
    w.put_next(l.index, index);
    w.put(label_bits(l));
    w.put_next(static_cast<std::uint64_t>(l.first_ms), first);
    w.put_next(static_cast<std::uint64_t>(l.last_ms), last);
  }
  return w;
}

/// The inverse of encode_labels; false when the bytes do not hold `labels` valid labels.
bool decode_labels(std::string_view bytes, std::size_t count, std::vector<OwnedLabel>& labels) {
  VarintReader in(bytes.data(), bytes.data() + bytes.size());
  labels.resize(count);
  std::uint32_t acquisition = 0, index = 0;
  std::uint64_t bits = 0, first = 0, last = 0;
  for (OwnedLabel& l : labels) {
    if (!in.get_next(acquisition) || !in.get_next(index) || !in.get(bits) || !in.get_next(first) ||
        !in.get_next(last)) {
      return false;
    }
    if ((bits & 3) > 2 || bits >> 14 != 0) return false;
    l = {.acquisition = acquisition,
         .index = index,
         .state = static_cast<TriangleState>(bits & 3),
         .kept = static_cast<std::uint8_t>((bits >> 2) & 1),
         .sustainable = static_cast<std::uint8_t>((bits >> 3) & 1),
         .refutes = static_cast<std::uint8_t>((bits >> 4) & 1),
         .selected = static_cast<std::uint8_t>((bits >> 5) & 1),
         .notes = static_cast<std::uint8_t>(bits >> 6),
         .first_ms = static_cast<std::int64_t>(first),
         .last_ms = static_cast<std::int64_t>(last)};
  }
  return in.at_end();
}

/// After an upgrade every result of the older format is processed again: said once, not once
/// per tile (a city has tens of thousands).
std::nullopt_t older_version(const std::filesystem::path& file) {
  static std::atomic<bool> said{false};
  if (!said.exchange(true)) {
    log::warn("{}: not a tile result of this version (made by an older citymesh?); such tiles are processed again",
              file.string());
  } else {
    log::debug("{}: not a tile result of this version; the tile is processed again", file.string());
  }
  return std::nullopt;
}

/// A file written part by part with the checksum of everything written so far, which ends it.
class ChecksummedFile {
 public:
  explicit ChecksummedFile(const std::filesystem::path& path) : file_(path) {}
  void write(std::string_view bytes) {
    file_.write(bytes);
    sum_.add(bytes.data(), bytes.size());
  }
  template <class T>
  void write_raw(const T& value) {
    write(std::string_view(reinterpret_cast<const char*>(&value), sizeof value));
  }
  /// Appends the checksum, then flushes, fsyncs and renames (AtomicFile::commit).
  void commit() {
    const std::uint64_t sum = sum_.value();
    file_.write(&sum, sizeof sum);
    file_.commit();
  }

 private:
  AtomicFile file_;
  BulkChecksum sum_;
};

/// The sections of a result after its header, in the order the file holds them: labels,
/// pairs, refuted copies, passes, then `pieces` pieces (each its 8-byte size and its bytes).
struct ResultSections {
  std::string_view labels, pairs, refuted;
  std::span<const std::uint32_t> passes;
  std::size_t pieces = 0;
};

/// Writes `h` (its section sizes set from `s`) and the sections; `piece_bytes(a)` gives the
/// bytes of piece a when they are written, not before: a spinning scanner's tile result is a
/// 0.3 GB file, and gathering it (grown by doubling) beside the sections took that tile's peak
/// from 1.9 to 2.5 GB.
template <class PieceBytes>
void write_result(const std::filesystem::path& file, ResultHeader h, const ResultSections& s,
                  const PieceBytes& piece_bytes) {
  h.label_bytes = s.labels.size();
  h.pair_bytes = s.pairs.size();
  h.refuted_bytes = s.refuted.size();
  h.passes = s.passes.size();
  h.acquisitions = s.pieces;
  ChecksummedFile out(file);
  out.write_raw(h);
  out.write(s.labels);
  out.write(s.pairs);
  out.write(s.refuted);
  out.write(std::string_view(reinterpret_cast<const char*>(s.passes.data()), s.passes.size_bytes()));
  for (std::size_t a = 0; a < s.pieces; ++a) {
    const auto block = piece_bytes(a);
    out.write_raw(std::uint64_t{block.size()});
    out.write(block);
  }
  out.commit();
}

}  // namespace

void write_tile_result(const std::filesystem::path& file, const TileResult& r, ResultDigests digests) {
  const VarintWriter labels = encode_labels(r.labels), refuted = encode_deltas<RefutedCopy>(r.refuted, kRefutedFields);
  ResultHeader h{};
  std::memcpy(h.magic, kMagic, sizeof kMagic);
  h.fingerprint = digests.result;
  h.i = r.key.i;
  h.j = r.key.j;
  h.labels = r.labels.size();
  h.pairs = r.pairs.size();
  h.triangles_in_tile = r.triangles_in_tile;
  h.seconds_read = r.seconds_read;
  h.seconds_detect = r.seconds_detect;
  h.seconds_mosaic = r.seconds_mosaic;
  h.change = figures_of(r.change);
  h.refuted = r.refuted.size();
  h.inputs_fingerprint = digests.inputs;
  h.settled_fingerprint = r.settled_fingerprint;
  write_result(file, h, {labels.bytes(), r.pairs.bytes(), refuted.bytes(), r.passes, r.selected.size()},
               [&](std::size_t a) {
                 const TilePiece& p = r.selected[a];
                 return p.triangle_count() == 0 ? std::string() : encode_tile_block(p);
               });
}

namespace {

/// A result file whose checksum, magic, fingerprint and section sizes passed: the header and
/// the bytes, for the sections to be decoded.
struct CheckedResult {
  ResultHeader header{};
  std::string bytes;

  [[nodiscard]] std::string_view labels() const { return section(sizeof header, header.label_bytes); }
  [[nodiscard]] std::string_view pairs() const { return section(pairs_at(), header.pair_bytes); }
  [[nodiscard]] std::string_view refuted() const { return section(refuted_at(), header.refuted_bytes); }
  [[nodiscard]] std::vector<std::uint32_t> passes() const {
    std::vector<std::uint32_t> out(header.passes);
    std::memcpy(out.data(), bytes.data() + passes_at(), out.size() * sizeof(std::uint32_t));
    return out;
  }
  /// Each piece's bytes (pieces_fit checked their sizes).
  [[nodiscard]] std::vector<std::string_view> pieces() const {
    std::vector<std::string_view> out;
    std::size_t at = pieces_at();
    for (std::uint64_t a = 0; a < header.acquisitions; ++a) {
      std::uint64_t size = 0;
      std::memcpy(&size, bytes.data() + at, sizeof size);
      out.push_back(section(at + sizeof size, size));
      at += sizeof size + size;
    }
    return out;
  }

  [[nodiscard]] std::size_t pairs_at() const { return sizeof header + header.label_bytes; }
  [[nodiscard]] std::size_t refuted_at() const { return pairs_at() + header.pair_bytes; }
  [[nodiscard]] std::size_t passes_at() const { return refuted_at() + header.refuted_bytes; }
  [[nodiscard]] std::size_t pieces_at() const { return passes_at() + header.passes * sizeof(std::uint32_t); }
  [[nodiscard]] std::string_view section(std::size_t at, std::size_t size) const {
    return std::string_view(bytes).substr(at, size);
  }
};

/// Says why a result is not used; nothing, for the reader to return.
std::nullopt_t stale(const std::filesystem::path& file, std::string_view why) {
  log::warn("{}: {}; the tile is processed again", file.string(), why);
  return std::nullopt;
}

/// Whether `passes` are acquisitions of the result, each once, in increasing order.
bool passes_fit(std::span<const std::uint32_t> passes, std::uint64_t acquisitions) {
  for (std::size_t k = 0; k < passes.size(); ++k) {
    if (passes[k] >= acquisitions || (k > 0 && passes[k] <= passes[k - 1])) return false;
  }
  return true;
}

/// Whether the `acquisitions` pieces from byte `at` (each an 8-byte size and its bytes) end
/// before the checksum, only the tile's `passes` with triangles, those from `listed` on
/// (acquisitions withdrawn since) empty.
bool pieces_fit(std::string_view bytes, std::size_t at, std::uint64_t acquisitions, std::size_t listed,
                std::span<const std::uint32_t> passes) {
  const std::size_t end = bytes.size() - sizeof(std::uint64_t);
  for (std::uint64_t a = 0; a < acquisitions; ++a) {
    std::uint64_t size = 0;
    if (end - at < sizeof size) return false;
    std::memcpy(&size, bytes.data() + at, sizeof size);
    at += sizeof size;
    if (size > end - at) return false;
    if (size > 0 && (a >= listed || !std::binary_search(passes.begin(), passes.end(), a))) return false;
    at += size;
  }
  return true;
}

/// What is wrong with `bytes` as a whole result of this version, in the order it is checked.
enum class ResultDamage { none, truncated, older_version, checksum };
ResultDamage result_damage(std::string_view bytes) {
  std::uint64_t sum = 0;
  if (bytes.size() < sizeof kMagic) return ResultDamage::truncated;
  if (std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0) return ResultDamage::older_version;
  if (bytes.size() < sizeof(ResultHeader) + sizeof sum) return ResultDamage::truncated;
  std::memcpy(&sum, bytes.data() + bytes.size() - sizeof sum, sizeof sum);
  if (bulk_checksum(bytes.data(), bytes.size() - sizeof sum) != sum) return ResultDamage::checksum;
  return ResultDamage::none;
}

/// The result in `file` when it is whole and was made under `digest` (any digest: nothing),
/// read under the numbering of a config listing `listed` acquisitions (pieces of those past
/// it refused; any: as restamp_tile_result reads it, to renumber).
std::optional<CheckedResult> checked_result(const std::filesystem::path& file, std::optional<std::uint64_t> digest,
                                            std::size_t listed) {
  std::optional<std::string> read = read_file_bytes(file);
  if (!read) return std::nullopt;
  const std::string_view bytes = *read;
  switch (result_damage(bytes)) {
    case ResultDamage::truncated:
      return stale(file, "truncated");
    case ResultDamage::older_version:
      return older_version(file);
    case ResultDamage::checksum:
      return stale(file, "checksum mismatch");
    case ResultDamage::none:
      break;
  }
  ResultHeader h{};
  std::memcpy(&h, bytes.data(), sizeof h);
  // Made from other inputs: another config (--force was given), a rewritten or added
  // acquisition in this tile, a dependency redone, or its passes renumbered.
  if (digest && h.fingerprint != *digest) return std::nullopt;
  const std::size_t body = bytes.size() - sizeof(std::uint64_t) - sizeof h;  // less the checksum
  // Counts are checked against the section sizes (a varint takes a byte at least, a piece
  // its 8-byte size) before anything is allocated. A result made before acquisitions were
  // appended holds fewer pieces, one made before the last ones were withdrawn more (empty):
  // the digest says the tile has none of the others.
  if (h.acquisitions > body / sizeof(std::uint64_t) || h.label_bytes > body || h.pair_bytes > body - h.label_bytes ||
      h.refuted_bytes > body - h.label_bytes - h.pair_bytes ||
      h.passes > (body - h.label_bytes - h.pair_bytes - h.refuted_bytes) / sizeof(std::uint32_t) ||
      h.labels > h.label_bytes / kVarintsPerLabel || h.pairs > h.pair_bytes / kVarintsPerPair ||
      h.refuted > h.refuted_bytes / kRefutedFields.size()) {
    return stale(file, "counts do not fit");
  }
  CheckedResult checked{h, std::move(*read)};
  const std::vector<std::uint32_t> passes = checked.passes();
  if (!passes_fit(passes, h.acquisitions)) return stale(file, "its list of acquisitions is damaged");
  if (!pieces_fit(checked.bytes, checked.pieces_at(), h.acquisitions, listed, passes)) {
    return stale(file, "its pieces do not fit, or hold triangles of an acquisition the config no longer lists");
  }
  return checked;
}

}  // namespace

std::optional<TileResult> read_tile_result(const std::filesystem::path& file, std::uint64_t digest,
                                           const TileStore& store, TileResultSections sections) {
  const std::optional<CheckedResult> checked = checked_result(file, digest, store.triangles.size());
  if (!checked) return std::nullopt;
  const ResultHeader& h = checked->header;
  TileResult r;
  r.key = {h.i, h.j};
  r.triangles_in_tile = h.triangles_in_tile;
  r.seconds_read = h.seconds_read;
  r.seconds_detect = h.seconds_detect;
  r.seconds_mosaic = h.seconds_mosaic;
  r.change = stats_of(h.change);
  r.settled_fingerprint = h.settled_fingerprint;
  r.passes = checked->passes();
  if (!decode_labels(checked->labels(), h.labels, r.labels)) return stale(file, "damaged labels");
  if (sections.pairs) {
    std::optional<LabelPairList> pairs = LabelPairList::from_bytes(std::string(checked->pairs()), h.pairs);
    if (!pairs) return stale(file, "damaged pairs");
    r.pairs = std::move(*pairs);
  }
  if (!decode_deltas(checked->refuted(), h.refuted, kRefutedFields, r.refuted)) {
    return stale(file, "damaged refuted copies");
  }
  const Vec3d origin = TileGrid(store.grid).corner(r.key);
  const std::vector<std::string_view> pieces = checked->pieces();
  for (std::uint32_t a = 0; a < pieces.size() && a < store.triangles.size(); ++a) {  // withdrawn since: empty
    TilePiece piece;
    piece.mesh.origin = origin;
    if (sections.selected && !pieces[a].empty()) piece = decode_tile_blocks(pieces[a], origin, a, file.string());
    r.selected.push_back(std::move(piece));
  }
  while (r.selected.size() < store.triangles.size()) {
    r.selected.emplace_back();
    r.selected.back().mesh.origin = origin;
  }
  return r;
}

bool tile_result_is_finished(const std::filesystem::path& file, std::uint64_t digest, const TileStore& store) {
  return checked_result(file, digest, store.triangles.size()).has_value();
}

std::optional<std::vector<OwnedLabel>> read_tile_labels(const std::filesystem::path& file, std::uint64_t digest,
                                                        const TileStore& store) {
  const std::optional<CheckedResult> checked = checked_result(file, digest, store.triangles.size());
  if (!checked) return std::nullopt;
  std::vector<OwnedLabel> labels;
  if (!decode_labels(checked->labels(), checked->header.labels, labels)) return stale(file, "damaged labels");
  return labels;
}

std::optional<ResultOrigin> tile_result_origin(const std::filesystem::path& file) {
  // The header alone: after a change of settings every tile asks, and reading its whole
  // result (megabytes) to be told "other inputs" would cost a city's worth of reads.
  ResultHeader h{};
  std::ifstream in(file, std::ios::binary);
  if (!in.read(reinterpret_cast<char*>(&h), sizeof h)) return std::nullopt;
  if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0) return std::nullopt;
  return ResultOrigin{h.fingerprint, h.inputs_fingerprint, h.settled_fingerprint, h.kept != 0};
}

std::optional<ResultOrigin> whole_tile_result_origin(const std::filesystem::path& file) {
  const std::optional<std::string> bytes = read_file_bytes(file);
  if (!bytes || result_damage(*bytes) != ResultDamage::none) return std::nullopt;
  ResultHeader h{};
  std::memcpy(&h, bytes->data(), sizeof h);
  return ResultOrigin{h.fingerprint, h.inputs_fingerprint, h.settled_fingerprint, h.kept != 0};
}

namespace {

/// The k-th of `from` as the k-th of `to`; nothing for an acquisition `from` does not hold.
std::optional<std::uint32_t> renumbered(std::span<const std::uint32_t> from, std::span<const std::uint32_t> to,
                                        std::uint32_t a) {
  const auto it = std::lower_bound(from.begin(), from.end(), a);
  if (it == from.end() || *it != a) return std::nullopt;
  return to[static_cast<std::size_t>(it - from.begin())];
}

/// Writes `checked` again with every acquisition index `from[k]` made `to[k]`, under the
/// digest `result`, marked kept, with `acquisitions` pieces; false when it names an
/// acquisition `from` does not hold (then nothing is written). Both lists increase, so the
/// map keeps the order of every sorted list: the file is what processing the tile under the
/// new numbering writes (but for its timings).
bool write_renumbered(const std::filesystem::path& file, const CheckedResult& checked,
                      std::span<const std::uint32_t> from, std::span<const std::uint32_t> to, std::uint64_t result,
                      std::size_t acquisitions) {
  const ResultHeader& h = checked.header;
  std::vector<OwnedLabel> labels;
  std::vector<RefutedCopy> refuted;
  const std::optional<LabelPairList> pairs = LabelPairList::from_bytes(std::string(checked.pairs()), h.pairs);
  if (!pairs || !decode_labels(checked.labels(), h.labels, labels) ||
      !decode_deltas(checked.refuted(), h.refuted, kRefutedFields, refuted)) {
    return false;
  }
  const auto map = [&](std::uint32_t& a) {
    const std::optional<std::uint32_t> b = renumbered(from, to, a);
    if (b) a = *b;
    return b.has_value();
  };
  for (OwnedLabel& l : labels) {
    if (!map(l.acquisition)) return false;
  }
  for (RefutedCopy& c : refuted) {
    if (!map(c.acquisition)) return false;
  }
  LabelPairList mapped;
  mapped.reserve(pairs->bytes().size());
  for (LabelPair p : *pairs) {
    if (!map(p.a_acquisition) || !map(p.b_acquisition)) return false;
    mapped.push_back(p);
  }
  const std::vector<std::string_view> pieces = checked.pieces();
  std::vector<std::string_view> moved(acquisitions);
  for (std::size_t k = 0; k < from.size(); ++k) {
    if (to[k] >= acquisitions) return false;
    moved[to[k]] = pieces[from[k]];  // passes_fit: from[k] < pieces.size()
  }
  ResultHeader renamed = h;
  renamed.fingerprint = result;
  renamed.kept = 1;
  const VarintWriter label_bytes = encode_labels(labels);
  const VarintWriter refuted_bytes = encode_deltas<RefutedCopy>(refuted, kRefutedFields);
  write_result(file, renamed, {label_bytes.bytes(), mapped.bytes(), refuted_bytes.bytes(), to, acquisitions},
               [&](std::size_t a) { return moved[a]; });
  return true;
}

}  // namespace

bool restamp_tile_result(const std::filesystem::path& file, const TileStore& store, const ResultOrigin& made_from,
                         std::uint64_t result, std::span<const std::uint32_t> passes) {
  // Any number of acquisitions: a pass removed before the newest moves the later ones' pieces
  // down (the renumbering below), and pieces lie only at the result's passes (checked).
  std::optional<CheckedResult> checked = checked_result(file, std::nullopt, SIZE_MAX);
  // Only a whole result made from what the caller was told: the file may have been replaced
  // since it looked.
  if (!checked) return false;
  const ResultHeader& h = checked->header;
  if (h.inputs_fingerprint != made_from.inputs || h.settled_fingerprint != made_from.settled) return false;
  const std::vector<std::uint32_t> held = checked->passes();
  if (held.size() != passes.size()) return false;
  if (!std::ranges::equal(held, passes)) {
    return write_renumbered(file, *checked, held, passes, result, store.triangles.size());
  }
  std::string& bytes = checked->bytes;
  std::memcpy(bytes.data() + offsetof(ResultHeader, fingerprint), &result, sizeof result);
  const std::uint64_t kept = 1;
  std::memcpy(bytes.data() + offsetof(ResultHeader, kept), &kept, sizeof kept);
  const std::uint64_t sum = bulk_checksum(bytes.data(), bytes.size() - sizeof sum);
  std::memcpy(bytes.data() + bytes.size() - sizeof sum, &sum, sizeof sum);
  write_file_atomically(file, bytes);
  return true;
}

}  // namespace citymesh::app
