// SPDX-License-Identifier: MIT
#include "citymesh/encode/glb.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <set>

#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"

namespace citymesh {

namespace {

constexpr std::uint32_t kGlbMagic = 0x46546C67;   // "glTF"
constexpr std::uint32_t kJsonChunk = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kBinChunk = 0x004E4942;   // "BIN\0"
constexpr int kFloat = 5126, kUnsignedInt = 5125, kUnsignedShort = 5123, kUnsignedByte = 5121;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

/// glTF is y-up; our tiles are z-up: (x, y, z) -> (x, z, -y), column-major.
const std::vector<double> kZUpToYUp{1, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1};

/// The binary chunk under construction and its buffer views (8-byte aligned, as
/// EXT_structural_metadata asks).
class BinBuilder {
 public:
  int add(std::span<const std::uint8_t> bytes, int target = 0, int stride = 0) {
    bin_.resize((bin_.size() + 7) / 8 * 8, 0);
    nlohmann::json view{{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", bytes.size()}};
    if (target != 0) view["target"] = target;
    if (stride != 0) view["byteStride"] = stride;
    bin_.insert(bin_.end(), bytes.begin(), bytes.end());
    views_.push_back(std::move(view));
    return static_cast<int>(views_.size() - 1);
  }
  template <typename T>
  int add_values(std::span<const T> values, int target = 0) {
    return add({reinterpret_cast<const std::uint8_t*>(values.data()), values.size_bytes()}, target);
  }
  /// Vertex attribute elements padded to 4 bytes, as glTF requires.
  template <typename T>
  int add_vertex_attribute(std::span<const T> values) {
    const std::size_t stride = (sizeof(T) + 3) / 4 * 4;
    if (stride == sizeof(T)) return add_values(values, kArrayBuffer);
    std::vector<std::uint8_t> padded(values.size() * stride, 0);
    for (std::size_t i = 0; i < values.size(); ++i) std::memcpy(&padded[i * stride], &values[i], sizeof(T));
    return add(padded, kArrayBuffer, static_cast<int>(stride));
  }
  [[nodiscard]] const std::vector<std::uint8_t>& bytes() const { return bin_; }
  [[nodiscard]] const nlohmann::json& views() const { return views_; }

 private:
  std::vector<std::uint8_t> bin_;
  nlohmann::json views_ = nlohmann::json::array();
};

nlohmann::json accessor(int component_type, std::size_t count, const char* type) {
  return {{"componentType", component_type}, {"count", count}, {"type", type}};
}

nlohmann::json position_accessor(std::span<const Vec3f> positions) {
  std::array<float, 3> lo{0, 0, 0}, hi{0, 0, 0};
  if (!positions.empty()) {
    lo = hi = {positions[0].x, positions[0].y, positions[0].z};
    for (const Vec3f& p : positions) {
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], p[k]);
        hi[k] = std::max(hi[k], p[k]);
      }
    }
  }
  nlohmann::json a = accessor(kFloat, positions.size(), "VEC3");
  a["min"] = lo;
  a["max"] = hi;
  return a;
}

/// Strings of a property table column: the concatenated UTF-8 bytes and count+1 offsets.
void add_string_column(BinBuilder& bin, nlohmann::json& properties, const char* name,
                       const std::vector<std::string>& strings) {
  std::vector<std::uint8_t> values;
  std::vector<std::uint32_t> offsets{0};
  for (const std::string& s : strings) {
    values.insert(values.end(), s.begin(), s.end());
    offsets.push_back(static_cast<std::uint32_t>(values.size()));
  }
  properties[name] = {{"values", bin.add(values)},
                      {"stringOffsets", bin.add_values(std::span<const std::uint32_t>(offsets))},
                      {"stringOffsetType", "UINT32"}};
}

/// EXT_structural_metadata: the acquisition class and its property table.
nlohmann::json acquisition_metadata(BinBuilder& bin, const std::vector<GlbAcquisition>& acquisitions) {
  std::vector<std::string> names, dates;
  for (const GlbAcquisition& a : acquisitions) {
    names.push_back(a.name);
    dates.push_back(a.date);
  }
  nlohmann::json properties = nlohmann::json::object();
  add_string_column(bin, properties, "name", names);
  add_string_column(bin, properties, "date", dates);
  nlohmann::json schema{
      {"id", "citymesh"},
      {"classes",
       {{"acquisition",
         {{"description", "A mobile-mapping acquisition; feature id k is acquisition k of the run's config"},
          {"properties",
           {{"name", {{"type", "STRING"}}},
            {"date", {{"type", "STRING"}, {"description", "acquisition date, ISO 8601 UTC"}}}}}}}}}};
  return {{"schema", std::move(schema)},
          {"propertyTables",
           {{{"class", "acquisition"}, {"count", acquisitions.size()}, {"properties", std::move(properties)}}}}};
}

std::size_t distinct_features(std::span<const std::uint16_t> ids) {
  std::set<std::uint16_t> seen(ids.begin(), ids.end());
  seen.erase(kNullFeatureId);
  return seen.size();
}

void check_mesh(const DracoMeshView& mesh) {
  const std::size_t n = mesh.positions.size();
  auto sized = [n](std::size_t s) { return s == 0 || s == n; };
  if (!sized(mesh.feature_ids.size()) || !sized(mesh.intensities.size()) || !sized(mesh.colors.size())) {
    throw ProcessingError("glb: a vertex attribute does not have one value per vertex");
  }
  for (const Triangle& t : mesh.triangles) {
    if (t[0] >= n || t[1] >= n || t[2] >= n) throw ProcessingError("glb: a triangle refers to a missing vertex");
  }
}

/// Accessors (and, without Draco, their buffer views) of the mesh; returns the primitive.
nlohmann::json mesh_primitive(const DracoMeshView& mesh, const GlbParams& params, BinBuilder& bin,
                              nlohmann::json& accessors) {
  auto add_accessor = [&](nlohmann::json a) {
    accessors.push_back(std::move(a));
    return static_cast<int>(accessors.size() - 1);
  };
  nlohmann::json primitive{{"mode", 4}, {"attributes", nlohmann::json::object()}};
  DecodedMesh decoded;
  DracoAttributeIds ids;
  if (params.draco) {
    DracoEncoded encoded = draco_encode(mesh, params.draco_params);
    // Counts and bounds are those of the decoded mesh: Draco may split vertices and
    // quantization moves positions by up to half a step.
    decoded = draco_decode(encoded.bytes, encoded.ids);
    ids = encoded.ids;
    nlohmann::json attributes{{"POSITION", ids.position}};
    if (ids.feature_id >= 0) attributes[kFeatureIdAttribute] = ids.feature_id;
    if (ids.intensity >= 0) attributes[kIntensityAttribute] = ids.intensity;
    if (ids.color >= 0) attributes["COLOR_0"] = ids.color;
    primitive["extensions"]["KHR_draco_mesh_compression"] = {{"bufferView", bin.add(encoded.bytes)},
                                                             {"attributes", std::move(attributes)}};
  }
  const std::span<const Vec3f> positions = params.draco ? std::span<const Vec3f>(decoded.positions) : mesh.positions;
  const std::size_t vertices = positions.size();
  const std::size_t corners = (params.draco ? decoded.triangles.size() : mesh.triangles.size()) * 3;
  nlohmann::json position = position_accessor(positions);
  nlohmann::json indices = accessor(kUnsignedInt, corners, "SCALAR");
  nlohmann::json feature_ids = accessor(kUnsignedShort, vertices, "SCALAR");
  nlohmann::json intensities = accessor(kFloat, vertices, "SCALAR");
  nlohmann::json colors = accessor(kUnsignedByte, vertices, "VEC3");
  colors["normalized"] = true;
  if (!params.draco) {
    position["bufferView"] = bin.add_vertex_attribute(mesh.positions);
    indices["bufferView"] = bin.add_values(mesh.triangles, kElementArrayBuffer);
    if (!mesh.feature_ids.empty()) feature_ids["bufferView"] = bin.add_vertex_attribute(mesh.feature_ids);
    if (!mesh.intensities.empty()) intensities["bufferView"] = bin.add_vertex_attribute(mesh.intensities);
    if (!mesh.colors.empty()) colors["bufferView"] = bin.add_vertex_attribute(mesh.colors);
  }
  primitive["attributes"]["POSITION"] = add_accessor(std::move(position));
  primitive["indices"] = add_accessor(std::move(indices));
  if (!mesh.feature_ids.empty()) primitive["attributes"][kFeatureIdAttribute] = add_accessor(std::move(feature_ids));
  if (!mesh.intensities.empty()) primitive["attributes"][kIntensityAttribute] = add_accessor(std::move(intensities));
  if (!mesh.colors.empty()) primitive["attributes"]["COLOR_0"] = add_accessor(std::move(colors));
  return primitive;
}

void append_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
}

std::uint32_t read_u32(std::span<const std::uint8_t> b, std::size_t at) {
  std::uint32_t v = 0;
  for (int k = 3; k >= 0; --k) v = (v << 8) | b[at + static_cast<std::size_t>(k)];
  return v;
}

std::vector<std::uint8_t> assemble_glb(const nlohmann::json& json, std::span<const std::uint8_t> bin) {
  std::string text = json.dump();
  text.resize((text.size() + 3) / 4 * 4, ' ');
  const std::size_t bin_length = (bin.size() + 3) / 4 * 4;
  const std::size_t total = 12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin_length);
  if (total > std::numeric_limits<std::uint32_t>::max()) throw ProcessingError("glb: the tile exceeds 4 GiB");
  std::vector<std::uint8_t> out;
  out.reserve(total);
  append_u32(out, kGlbMagic);
  append_u32(out, 2);
  append_u32(out, static_cast<std::uint32_t>(total));
  append_u32(out, static_cast<std::uint32_t>(text.size()));
  append_u32(out, kJsonChunk);
  out.insert(out.end(), text.begin(), text.end());
  if (!bin.empty()) {
    append_u32(out, static_cast<std::uint32_t>(bin_length));
    append_u32(out, kBinChunk);
    out.insert(out.end(), bin.begin(), bin.end());
    out.resize(total, 0);
  }
  return out;
}

}  // namespace

std::uint64_t glb_primitive_digest(const DracoMeshView& mesh, const DracoEncodeParams& params) {
  constexpr std::uint64_t kFormat = 1;  // bumped when mesh_primitive writes something else
  BulkChecksum sum;
  sum.add_value(kFormat);
  const std::string_view draco = draco_version();  // another Draco may encode otherwise
  sum.add(draco.data(), draco.size());
  sum.add_array(mesh.positions);
  sum.add_array(mesh.triangles);
  sum.add_array(mesh.feature_ids);
  sum.add_array(mesh.intensities);
  sum.add_array(mesh.colors);
  sum.add_value(std::int64_t{params.position_bits});
  sum.add_value(std::int64_t{params.speed});
  sum.add_value(params.lattice.has_value());
  if (params.lattice) {
    sum.add_value(params.lattice->origin);
    sum.add_value(params.lattice->range);
  }
  return sum.value();
}

std::vector<std::uint8_t> write_glb(const DracoMeshView& given, const GlbParams& params) {
  check_mesh(given);
  // A tile of stitch triangles only has no feature: no feature ids then (ids without the
  // acquisition table that EXT_mesh_features needs, at least one feature, would be a mesh
  // feature attribute no viewer can read).
  DracoMeshView mesh = given;
  if (distinct_features(mesh.feature_ids) == 0) mesh.feature_ids = {};
  BinBuilder bin;
  nlohmann::json accessors = nlohmann::json::array();
  nlohmann::json primitive;
  if (params.draco && params.primitives != nullptr) {
    // The Draco bytes are the primitive's only buffer view, added first: a kept primitive
    // gives the same views, and the glb the same bytes.
    const std::uint64_t digest = glb_primitive_digest(mesh, params.draco_params);
    if (std::optional<GlbPrimitive> kept = params.primitives->find(digest)) {
      bin.add(kept->draco);
      accessors = std::move(kept->accessors);
      primitive = std::move(kept->primitive);
    } else {
      primitive = mesh_primitive(mesh, params, bin, accessors);
      params.primitives->keep(digest, {primitive, accessors, bin.bytes()});
    }
  } else {
    primitive = mesh_primitive(mesh, params, bin, accessors);
  }
  nlohmann::json json{{"asset", {{"version", "2.0"}, {"generator", "citymesh"}}},
                      {"scene", 0},
                      {"scenes", {{{"nodes", {0}}}}},
                      {"nodes", {{{"mesh", 0}, {"matrix", kZUpToYUp}}}}};
  std::vector<std::string> used;
  if (params.draco) used.emplace_back("KHR_draco_mesh_compression");
  const std::size_t features = distinct_features(mesh.feature_ids);
  if (features > 0 && !params.acquisitions.empty()) {
    primitive["extensions"]["EXT_mesh_features"]["featureIds"] = {{{"featureCount", features},
                                                                   {"attribute", 0},
                                                                   {"propertyTable", 0},
                                                                   {"nullFeatureId", kNullFeatureId},
                                                                   {"label", "acquisition"}}};
    json["extensions"]["EXT_structural_metadata"] = acquisition_metadata(bin, params.acquisitions);
    used.emplace_back("EXT_mesh_features");
    used.emplace_back("EXT_structural_metadata");
  }
  json["meshes"] = {{{"primitives", {std::move(primitive)}}}};
  json["accessors"] = std::move(accessors);
  if (!bin.bytes().empty()) {
    json["bufferViews"] = bin.views();
    json["buffers"] = {{{"byteLength", bin.bytes().size()}}};
  }
  if (!used.empty()) json["extensionsUsed"] = used;
  if (params.draco) json["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  return assemble_glb(json, bin.bytes());
}

GlbFile parse_glb(std::span<const std::uint8_t> bytes, const std::string& name) {
  auto fail = [&](const std::string& what) { return InputError(fmt::format("{}: not a valid glb: {}", name, what)); };
  if (bytes.size() < 20) throw fail(fmt::format("{} bytes, shorter than a glb header", bytes.size()));
  if (read_u32(bytes, 0) != kGlbMagic) throw fail("bad magic (expected \"glTF\")");
  if (read_u32(bytes, 4) != 2) throw fail(fmt::format("version {} (expected 2)", read_u32(bytes, 4)));
  if (read_u32(bytes, 8) != bytes.size()) {
    throw fail(fmt::format("header length {} but the file has {} bytes", read_u32(bytes, 8), bytes.size()));
  }
  GlbFile out;
  std::size_t at = 12;
  for (int chunk = 0; at < bytes.size(); ++chunk) {
    if (bytes.size() - at < 8) throw fail("truncated chunk header");
    const std::uint32_t length = read_u32(bytes, at), type = read_u32(bytes, at + 4);
    if (length > bytes.size() - at - 8) throw fail(fmt::format("chunk {} runs past the end of the file", chunk));
    const auto data = bytes.subspan(at + 8, length);
    if (chunk == 0) {
      if (type != kJsonChunk) throw fail("the first chunk is not JSON");
      out.json = nlohmann::json::parse(data.begin(), data.end(), nullptr, false);
      if (out.json.is_discarded() || !out.json.is_object()) throw fail("the JSON chunk does not parse");
    } else if (chunk == 1 && type == kBinChunk) {
      out.bin.assign(data.begin(), data.end());
    }
    at += 8 + length;
  }
  if (out.json.is_null()) throw fail("no JSON chunk");
  return out;
}

namespace {

/// The bytes of buffer view `index` of the glb's binary chunk, checked.
std::span<const std::uint8_t> view_bytes(const GlbFile& glb, const nlohmann::json& index, const std::string& name) {
  const nlohmann::json& views = glb.json.value("bufferViews", nlohmann::json::array());
  if (!index.is_number_unsigned() || index.get<std::size_t>() >= views.size()) {
    throw InputError(fmt::format("{}: bufferView {} does not exist", name, index.dump()));
  }
  const nlohmann::json& view = views[index.get<std::size_t>()];
  const std::size_t offset = view.value("byteOffset", std::size_t{0}),
                    length = view.value("byteLength", std::size_t{0});
  if (offset > glb.bin.size() || length > glb.bin.size() - offset) {
    throw InputError(fmt::format("{}: bufferView {} lies outside the binary chunk", name, index.dump()));
  }
  return std::span<const std::uint8_t>(glb.bin).subspan(offset, length);
}

template <typename T>
std::vector<T> read_plain_accessor(const GlbFile& glb, int accessor_index, std::size_t components,
                                   const std::string& name) {
  const nlohmann::json& a = glb.json.at("accessors").at(static_cast<std::size_t>(accessor_index));
  const std::size_t count = a.at("count").get<std::size_t>();
  const auto bytes = view_bytes(glb, a.at("bufferView"), name);
  const nlohmann::json& view = glb.json["bufferViews"][a["bufferView"].get<std::size_t>()];
  const std::size_t element = sizeof(T) * components, stride = view.value("byteStride", element);
  const std::size_t offset = a.value("byteOffset", std::size_t{0});
  if (count > 0 && (offset + (count - 1) * stride + element > bytes.size())) {
    throw InputError(fmt::format("{}: accessor {} runs past its bufferView", name, accessor_index));
  }
  std::vector<T> out(count * components);
  for (std::size_t i = 0; i < count; ++i) std::memcpy(&out[i * components], &bytes[offset + i * stride], element);
  return out;
}

DecodedMesh read_plain_mesh(const GlbFile& glb, const nlohmann::json& primitive, const std::string& name) {
  const nlohmann::json& attributes = primitive.at("attributes");
  DecodedMesh m;
  const auto xyz = read_plain_accessor<float>(glb, attributes.at("POSITION").get<int>(), 3, name);
  for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) m.positions.push_back({xyz[i], xyz[i + 1], xyz[i + 2]});
  const auto corners = read_plain_accessor<std::uint32_t>(glb, primitive.at("indices").get<int>(), 1, name);
  for (std::size_t i = 0; i + 2 < corners.size(); i += 3)
    m.triangles.push_back({corners[i], corners[i + 1], corners[i + 2]});
  if (attributes.contains(kFeatureIdAttribute)) {
    m.feature_ids = read_plain_accessor<std::uint16_t>(glb, attributes[kFeatureIdAttribute].get<int>(), 1, name);
  }
  if (attributes.contains(kIntensityAttribute)) {
    m.intensities = read_plain_accessor<float>(glb, attributes[kIntensityAttribute].get<int>(), 1, name);
  }
  if (attributes.contains("COLOR_0")) {
    const auto rgb = read_plain_accessor<std::uint8_t>(glb, attributes["COLOR_0"].get<int>(), 3, name);
    for (std::size_t i = 0; i + 2 < rgb.size(); i += 3) m.colors.push_back({rgb[i], rgb[i + 1], rgb[i + 2]});
  }
  return m;
}

DecodedMesh read_draco_mesh(const GlbFile& glb, const nlohmann::json& draco, const std::string& name) {
  const nlohmann::json& attributes = draco.at("attributes");
  auto id = [&](const char* key) { return attributes.contains(key) ? attributes[key].get<int>() : -1; };
  const DracoAttributeIds ids{id("POSITION"), id(kFeatureIdAttribute), id(kIntensityAttribute), id("COLOR_0")};
  if (ids.position < 0) throw InputError(fmt::format("{}: the Draco extension has no POSITION", name));
  try {
    return draco_decode(view_bytes(glb, draco.at("bufferView"), name), ids);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", name, e.what()));
  }
}

}  // namespace

DecodedMesh read_glb_mesh(const GlbFile& glb, const std::string& name) {
  try {
    const nlohmann::json& primitive = glb.json.at("meshes").at(0).at("primitives").at(0);
    if (primitive.value("mode", 4) != 4) throw InputError(fmt::format("{}: the primitive is not TRIANGLES", name));
    const nlohmann::json* draco = nullptr;
    if (primitive.contains("extensions") && primitive["extensions"].contains("KHR_draco_mesh_compression")) {
      draco = &primitive["extensions"]["KHR_draco_mesh_compression"];
    }
    DecodedMesh m = draco ? read_draco_mesh(glb, *draco, name) : read_plain_mesh(glb, primitive, name);
    for (const Triangle& t : m.triangles) {
      if (std::max({t[0], t[1], t[2]}) >= m.positions.size()) {
        throw InputError(fmt::format("{}: a triangle refers to a missing vertex", name));
      }
    }
    return m;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: the glTF JSON does not describe a mesh: {}", name, e.what()));
  }
}

}  // namespace citymesh
