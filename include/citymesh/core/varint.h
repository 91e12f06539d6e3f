// SPDX-License-Identifier: MIT
// Variable-length integers for citymesh's bulk files (tile store blocks, tile results): LEB128
// bytes of zigzag deltas, so that ids and indices that mostly grow by one take a byte each
// instead of four or eight.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>

namespace citymesh {

/// The most bytes put() or put_next() takes for values of `bits` bits (put_next's zigzag
/// needs one bit more).
constexpr std::size_t max_varint_bytes(unsigned bits) { return (bits + 1 + 6) / 7; }

/// `d`, a difference modulo 2^64 read as signed, with its sign in the low bit: small either way.
constexpr std::uint64_t zigzag(std::uint64_t d) {
  return d << 1 ^ static_cast<std::uint64_t>(static_cast<std::int64_t>(d) >> 63);
}
/// The inverse of zigzag.
constexpr std::uint64_t unzigzag(std::uint64_t z) { return (z >> 1) ^ (~(z & 1) + 1); }

/// The bytes VarintWriter::put() takes for `v`.
constexpr std::size_t varint_size(std::uint64_t v) {
  std::size_t n = 1;
  for (; v >= 0x80; v >>= 7) ++n;
  return n;
}

/// Appends `v` as VarintWriter::put() writes it, to a list that grows (its size counted
/// beforehand with varint_size, or not known).
inline void append_varint(std::string& out, std::uint64_t v) {
  for (; v >= 0x80; v >>= 7) out.push_back(static_cast<char>(v | 0x80));
  out.push_back(static_cast<char>(v));
}

/// Reads a varint from bytes known to hold one (written by this process, or checked with
/// VarintReader first), without bounds checks: for lists decoded on hot paths.
template <class Unsigned, class Byte>
Unsigned read_trusted_varint(const Byte*& at) {
  static_assert(std::is_unsigned_v<Unsigned> && sizeof(Byte) == 1);
  Unsigned v = 0;
  for (unsigned shift = 0;; shift += 7) {
    const auto byte = static_cast<std::uint8_t>(*at++);
    v |= static_cast<Unsigned>(byte & 0x7fu) << shift;
    if (byte < 0x80) return v;
  }
}

/// Writes varints into a buffer sized beforehand: `room` must be at least the bytes every
/// value to come can take (see max_varint_bytes), so that no write checks the capacity. The
/// buffer is not zeroed: only the bytes written are ever touched.
class VarintWriter {
 public:
  explicit VarintWriter(std::size_t room = 0) : buffer_(new char[room]), capacity_(room), at_(buffer_.get()) {}

  /// Forgets what was written and makes sure of `room` bytes, keeping the buffer when it is
  /// large enough: a writer reused for block after block touches no fresh memory.
  void reset(std::size_t room) {
    if (room > capacity_) {
      buffer_.reset(new char[room]);
      capacity_ = room;
    }
    at_ = buffer_.get();
  }

  void put(std::uint64_t v) {
    // Through a local pointer: a char store may alias any object, `at_` included, so writing
    // through the member made the compiler load and store it again for every byte.
    char* at = at_;
    while (v >= 0x80) {
      *at++ = static_cast<char>(v | 0x80);
      v >>= 7;
    }
    *at++ = static_cast<char>(v);
    at_ = at;
  }

  /// `value - running` as a zigzag varint (small either way), then `running = value`: a
  /// sequence written against its own previous value. Wraps modulo 2^64, so any pair of values
  /// round-trips.
  template <class Unsigned>
  void put_next(Unsigned value, Unsigned& running) {
    static_assert(std::is_unsigned_v<Unsigned>);
    put(zigzag(std::uint64_t{value} - std::uint64_t{running}));
    running = value;
  }

  [[nodiscard]] std::string_view bytes() const {
    return {buffer_.get(), static_cast<std::size_t>(at_ - buffer_.get())};
  }

 private:
  std::unique_ptr<char[]> buffer_;
  std::size_t capacity_;
  char* at_;
};

/// Reads varints from a byte range; every read says whether it stayed inside the range, so a
/// damaged block is an error, never a read past its end.
class VarintReader {
 public:
  VarintReader(const char* begin, const char* end) : at_(begin), end_(end) {}

  [[nodiscard]] bool get(std::uint64_t& v) {
    v = 0;
    for (unsigned shift = 0; shift < 64; shift += 7) {
      if (at_ == end_) return false;
      const auto byte = static_cast<std::uint8_t>(*at_++);
      v |= std::uint64_t{byte & 0x7fu} << shift;
      if ((byte & 0x80u) == 0) return true;
    }
    return false;  // more than ten bytes: not a varint this writer made
  }

  /// The inverse of VarintWriter::put_next: the next value of the sequence, into `running`.
  [[nodiscard]] bool get_next(std::uint64_t& running) {
    std::uint64_t z = 0;
    if (!get(z)) return false;
    running += unzigzag(z);
    return true;
  }

  /// The same for a sequence of 32-bit values: false also when the next value does not fit.
  [[nodiscard]] bool get_next(std::uint32_t& running) {
    std::uint64_t value = running;
    if (!get_next(value) || value > UINT32_MAX) return false;
    running = static_cast<std::uint32_t>(value);
    return true;
  }

  [[nodiscard]] bool at_end() const { return at_ == end_; }

 private:
  const char* at_;
  const char* end_;
};

}  // namespace citymesh
