// SPDX-License-Identifier: MIT
// PLY header parsing and the size checks that keep absurd counts from being allocated.
#include <fmt/format.h>

#include <array>
#include <charconv>
#include <limits>

#include "citymesh/core/error.h"
#include "citymesh/io/ply.h"

namespace citymesh {

namespace {

struct ScalarName {
  std::string_view name;
  PlyScalar type;
};
constexpr std::array<ScalarName, 16> kScalarNames{{
    {"char", PlyScalar::int8},     {"int8", PlyScalar::int8},       {"uchar", PlyScalar::uint8},
    {"uint8", PlyScalar::uint8},   {"short", PlyScalar::int16},     {"int16", PlyScalar::int16},
    {"ushort", PlyScalar::uint16}, {"uint16", PlyScalar::uint16},   {"int", PlyScalar::int32},
    {"int32", PlyScalar::int32},   {"uint", PlyScalar::uint32},     {"uint32", PlyScalar::uint32},
    {"float", PlyScalar::float32}, {"float32", PlyScalar::float32}, {"double", PlyScalar::float64},
    {"float64", PlyScalar::float64},
}};

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

bool is_integer(PlyScalar t) { return t != PlyScalar::float32 && t != PlyScalar::float64; }

class HeaderParser {
 public:
  HeaderParser(std::string_view text, const std::filesystem::path& path) : text_(text), path_(path) {}

  PlyHeader parse() {
    std::string_view magic = next_line();
    if (magic != "ply") fail_at(0, "not a PLY file: the first line must be 'ply'");
    bool have_format = false;
    while (true) {
      if (pos_ >= text_.size()) fail("no 'end_header' line: the header is incomplete");
      std::string_view line = next_line();
      auto words = split_words(line);
      if (words.empty()) continue;
      const std::string_view keyword = words[0];
      if (keyword == "end_header") break;
      if (keyword == "format") {
        parse_format(words);
        have_format = true;
      } else if (keyword == "comment") {
        parse_comment(line);
      } else if (keyword == "obj_info") {
        continue;
      } else if (keyword == "element") {
        parse_element(words);
      } else if (keyword == "property") {
        parse_property(words);
      } else {
        fail(fmt::format("unknown header keyword '{}'", keyword));
      }
      if (!have_format && keyword != "comment" && keyword != "obj_info" && keyword != "format") {
        fail("the 'format' line must come before elements");
      }
    }
    if (!have_format) fail("no 'format' line");
    header_.header_bytes = pos_;
    return std::move(header_);
  }

 private:
  std::string_view next_line() {
    const std::size_t end = text_.find('\n', pos_);
    const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
    std::string_view line = text_.substr(pos_, stop - pos_);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos_ = end == std::string_view::npos ? text_.size() : end + 1;
    ++line_number_;
    return line;
  }

  [[noreturn]] void fail_at(std::size_t line, std::string_view why) const {
    if (line == 0) throw InputError(fmt::format("{}: {}", path_.string(), why));
    throw InputError(fmt::format("{}: header line {}: {}", path_.string(), line, why));
  }
  [[noreturn]] void fail(std::string_view why) const { fail_at(line_number_, why); }

  void parse_format(const std::vector<std::string_view>& w) {
    if (w.size() != 3) fail("expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
    if (w[1] == "ascii") {
      header_.format = PlyFormat::ascii;
    } else if (w[1] == "binary_little_endian") {
      header_.format = PlyFormat::binary_little_endian;
    } else if (w[1] == "binary_big_endian") {
      header_.format = PlyFormat::binary_big_endian;
    } else {
      fail(fmt::format("unknown format '{}'", w[1]));
    }
    if (w[2] != "1.0") fail(fmt::format("unsupported PLY version '{}' (only 1.0)", w[2]));
  }

  void parse_comment(std::string_view line) {
    std::string_view text = line.substr(std::min(line.size(), std::size_t{8}));
    header_.comments.emplace_back(text);
    auto w = split_words(text);
    std::size_t at = 0;
    if (!w.empty() && w[0] == "IGN") at = 1;
    if (w.size() < at + 2 || w[at] != "offset" || w[at + 1] != "Pos") return;
    if (w.size() != at + 5) fail("offset comment must be 'offset Pos E N H'");
    for (int i = 0; i < 3; ++i) {
      std::string_view s = w[at + 2 + static_cast<std::size_t>(i)];
      double v = 0;
      auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
      if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v)) {
        fail(fmt::format("offset comment: '{}' is not a number", s));
      }
      header_.offset[i] = v;
    }
  }

  void parse_element(const std::vector<std::string_view>& w) {
    if (w.size() != 3) fail("expected 'element <name> <count>'");
    for (const auto& e : header_.elements) {
      if (e.name == w[1]) fail(fmt::format("element '{}' is declared twice", w[1]));
    }
    PlyElement element;
    element.name = std::string(w[1]);
    auto [end, ec] = std::from_chars(w[2].data(), w[2].data() + w[2].size(), element.count);
    if (ec != std::errc() || end != w[2].data() + w[2].size()) {
      fail(fmt::format("element '{}': count '{}' is not a non-negative integer", w[1], w[2]));
    }
    header_.elements.push_back(std::move(element));
  }

  PlyScalar scalar(std::string_view name) const {
    for (const auto& s : kScalarNames) {
      if (s.name == name) return s.type;
    }
    fail(fmt::format("unknown property type '{}'", name));
  }

  void parse_property(const std::vector<std::string_view>& w) {
    if (header_.elements.empty()) fail("property before any element");
    PlyProperty p;
    if (w.size() >= 2 && w[1] == "list") {
      if (w.size() != 5) fail("expected 'property list <count type> <value type> <name>'");
      p.is_list = true;
      p.count_type = scalar(w[2]);
      p.type = scalar(w[3]);
      p.name = std::string(w[4]);
      if (!is_integer(p.count_type)) fail(fmt::format("list '{}': count type must be an integer", p.name));
    } else {
      if (w.size() != 3) fail("expected 'property <type> <name>'");
      p.type = scalar(w[1]);
      p.name = std::string(w[2]);
    }
    PlyElement& element = header_.elements.back();
    if (element.find(p.name) != nullptr) {
      fail(fmt::format("element '{}': property '{}' is declared twice", element.name, p.name));
    }
    element.properties.push_back(std::move(p));
  }

  std::string_view text_;
  const std::filesystem::path& path_;
  std::size_t pos_ = 0;
  std::size_t line_number_ = 0;
  PlyHeader header_;
};

std::uint64_t saturating_mul(std::uint64_t a, std::uint64_t b) {
  std::uint64_t product = 0;
  return __builtin_mul_overflow(a, b, &product) ? UINT64_MAX : product;
}
std::uint64_t saturating_add(std::uint64_t a, std::uint64_t b) {
  return a > UINT64_MAX - b ? UINT64_MAX : a + b;
}

/// Refuses counts that cannot fit in the file (a header claiming 10^12 vertices) before any
/// allocation, and elements the reader could loop over forever without consuming bytes.
void check_counts_fit(const PlyHeader& header, std::uint64_t file_size, const std::filesystem::path& path) {
  const std::uint64_t data_bytes = file_size >= header.header_bytes ? file_size - header.header_bytes : 0;
  std::uint64_t needed = 0;  // saturates at UINT64_MAX instead of wrapping
  for (const PlyElement& e : header.elements) {
    if (e.count > 0 && e.properties.empty()) {
      throw InputError(fmt::format("{}: element '{}' declares {} rows but no properties", path.string(),
                                   e.name, e.count));
    }
    needed = saturating_add(needed, saturating_mul(e.count, e.min_row_size(header.format)));
  }
  if (needed > data_bytes) {
    std::string counts;
    for (const PlyElement& e : header.elements) counts += fmt::format(" {} rows of '{}',", e.count, e.name);
    counts.pop_back();
    throw InputError(fmt::format(
        "{}: the header declares{} which need at least {} bytes of data, but only {} bytes follow "
        "the header (truncated file or wrong counts)",
        path.string(), counts, needed, data_bytes));
  }
}

}  // namespace

std::size_t ply_scalar_size(PlyScalar type) {
  switch (type) {
    case PlyScalar::int8:
    case PlyScalar::uint8: return 1;
    case PlyScalar::int16:
    case PlyScalar::uint16: return 2;
    case PlyScalar::int32:
    case PlyScalar::uint32:
    case PlyScalar::float32: return 4;
    case PlyScalar::float64: return 8;
  }
  return 0;
}

std::string_view ply_scalar_name(PlyScalar type) {
  switch (type) {
    case PlyScalar::int8: return "char";
    case PlyScalar::uint8: return "uchar";
    case PlyScalar::int16: return "short";
    case PlyScalar::uint16: return "ushort";
    case PlyScalar::int32: return "int";
    case PlyScalar::uint32: return "uint";
    case PlyScalar::float32: return "float";
    case PlyScalar::float64: return "double";
  }
  return "?";
}

std::optional<PlyScalar> parse_ply_scalar(std::string_view name) {
  for (const auto& s : kScalarNames) {
    if (s.name == name) return s.type;
  }
  return std::nullopt;
}

std::string_view ply_format_name(PlyFormat format) {
  switch (format) {
    case PlyFormat::ascii: return "ascii";
    case PlyFormat::binary_little_endian: return "binary_little_endian";
    case PlyFormat::binary_big_endian: return "binary_big_endian";
  }
  return "?";
}

std::optional<std::size_t> PlyElement::fixed_row_size() const {
  std::size_t size = 0;
  for (const PlyProperty& p : properties) {
    if (p.is_list) return std::nullopt;
    size += ply_scalar_size(p.type);
  }
  return size;
}

std::size_t PlyElement::min_row_size(PlyFormat format) const {
  if (format == PlyFormat::ascii) return 2 * properties.size();  // "0 " per value or empty list
  std::size_t size = 0;
  for (const PlyProperty& p : properties) size += ply_scalar_size(p.is_list ? p.count_type : p.type);
  return size;
}

const PlyProperty* PlyElement::find(std::string_view property) const {
  for (const PlyProperty& p : properties) {
    if (p.name == property) return &p;
  }
  return nullptr;
}

const PlyElement* PlyHeader::find(std::string_view element) const {
  for (const PlyElement& e : elements) {
    if (e.name == element) return &e;
  }
  return nullptr;
}

PlyHeader parse_ply_header(std::string_view text, std::uint64_t file_size, const std::filesystem::path& path) {
  PlyHeader header = HeaderParser(text, path).parse();
  check_counts_fit(header, file_size, path);
  return header;
}

}  // namespace citymesh
