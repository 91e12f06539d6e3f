// SPDX-License-Identifier: MIT
// The only source that includes Draco.
#include "citymesh/encode/draco_mesh.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/core/draco_version.h>
#include <draco/mesh/mesh.h>
#include <fmt/format.h>

#include "citymesh/core/error.h"

namespace citymesh {

std::string_view draco_version() { return draco::kDracoVersion; }

namespace {

/// Adds a per-vertex attribute with one value per point (identity mapping); returns its id.
template <typename T>
int add_attribute(draco::Mesh& mesh, draco::GeometryAttribute::Type type, draco::DataType data_type, int components,
                  bool normalized, std::span<const T> values) {
  if (values.empty()) return -1;
  if (values.size() != mesh.num_points()) {
    throw ProcessingError(fmt::format("draco: {} attribute values for {} vertices", values.size(), mesh.num_points()));
  }
  draco::GeometryAttribute attribute;
  attribute.Init(type, nullptr, static_cast<std::uint8_t>(components), data_type, normalized, sizeof(T), 0);
  const int index = mesh.AddAttribute(attribute, true, static_cast<std::uint32_t>(values.size()));
  draco::PointAttribute* added = mesh.attribute(index);
  for (std::uint32_t i = 0; i < values.size(); ++i) added->SetAttributeValue(draco::AttributeValueIndex(i), &values[i]);
  return static_cast<int>(added->unique_id());
}

const draco::PointAttribute* find_attribute(const draco::Mesh& mesh, int id, const char* what) {
  const draco::PointAttribute* a = mesh.GetAttributeByUniqueId(static_cast<std::uint32_t>(id));
  if (a == nullptr) throw InputError(fmt::format("draco: the mesh has no {} attribute (id {})", what, id));
  return a;
}

template <typename T, int Components, typename Store>
std::vector<T> read_attribute(const draco::Mesh& mesh, int id, const char* what, Store store) {
  if (id < 0) return {};
  const draco::PointAttribute* a = find_attribute(mesh, id, what);
  if (a->num_components() != Components) {
    throw InputError(fmt::format("draco: the {} attribute has {} components, not {}", what,
                                 static_cast<int>(a->num_components()), Components));
  }
  std::vector<T> out(mesh.num_points());
  for (draco::PointIndex p(0); p < mesh.num_points(); ++p) out[p.value()] = store(*a, p);
  return out;
}

}  // namespace

DracoEncoded draco_encode(const DracoMeshView& view, const DracoEncodeParams& params) {
  if (params.position_bits < 1 || params.position_bits > 30 || params.speed < 0 || params.speed > 10) {
    throw ProcessingError(fmt::format("draco: position_bits {} (1..30) or speed {} (0..10) out of range",
                                      params.position_bits, params.speed));
  }
  draco::Mesh mesh;
  mesh.set_num_points(static_cast<std::uint32_t>(view.positions.size()));
  DracoEncoded out;
  out.ids.position =
      add_attribute(mesh, draco::GeometryAttribute::POSITION, draco::DT_FLOAT32, 3, false, view.positions);
  out.ids.feature_id =
      add_attribute(mesh, draco::GeometryAttribute::GENERIC, draco::DT_UINT16, 1, false, view.feature_ids);
  out.ids.intensity =
      add_attribute(mesh, draco::GeometryAttribute::GENERIC, draco::DT_FLOAT32, 1, false, view.intensities);
  out.ids.color = add_attribute(mesh, draco::GeometryAttribute::COLOR, draco::DT_UINT8, 3, true, view.colors);
  for (const Triangle& t : view.triangles) {
    if (t[0] >= view.positions.size() || t[1] >= view.positions.size() || t[2] >= view.positions.size()) {
      throw ProcessingError("draco: a triangle refers to a missing vertex");
    }
    mesh.AddFace({draco::PointIndex(t[0]), draco::PointIndex(t[1]), draco::PointIndex(t[2])});
  }
  draco::Encoder encoder;
  if (params.lattice) {
    encoder.SetAttributeExplicitQuantization(draco::GeometryAttribute::POSITION, params.position_bits, 3,
                                             params.lattice->origin.data(), params.lattice->range);
  } else {
    encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, params.position_bits);
  }
  encoder.SetSpeedOptions(params.speed, params.speed);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(mesh, &buffer);
  if (!status.ok()) throw ProcessingError(fmt::format("draco: encoding failed: {}", status.error_msg_string()));
  out.bytes.assign(buffer.data(), buffer.data() + buffer.size());
  return out;
}

DecodedMesh draco_decode(std::span<const std::uint8_t> data, const DracoAttributeIds& ids) {
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(data.data()), data.size());
  draco::Decoder decoder;
  auto result = decoder.DecodeMeshFromBuffer(&buffer);
  if (!result.ok()) throw InputError(fmt::format("draco: cannot decode: {}", result.status().error_msg_string()));
  const std::unique_ptr<draco::Mesh> mesh = std::move(result).value();
  int position_id = ids.position;
  if (position_id < 0) {
    const draco::PointAttribute* p = mesh->GetNamedAttribute(draco::GeometryAttribute::POSITION);
    if (p == nullptr) throw InputError("draco: the mesh has no POSITION attribute");
    position_id = static_cast<int>(p->unique_id());
  }
  DecodedMesh out;
  out.positions = read_attribute<Vec3f, 3>(*mesh, position_id, "POSITION", [](const auto& a, draco::PointIndex p) {
    float xyz[3];
    a.GetMappedValue(p, xyz);
    return Vec3f{xyz[0], xyz[1], xyz[2]};
  });
  out.feature_ids =
      read_attribute<std::uint16_t, 1>(*mesh, ids.feature_id, "feature id", [](const auto& a, draco::PointIndex p) {
        std::uint16_t v = 0;
        a.ConvertValue(a.mapped_index(p), &v);
        return v;
      });
  out.intensities = read_attribute<float, 1>(*mesh, ids.intensity, "intensity", [](const auto& a, draco::PointIndex p) {
    float v = 0;
    a.ConvertValue(a.mapped_index(p), &v);
    return v;
  });
  out.colors = read_attribute<Rgb8, 3>(*mesh, ids.color, "colour", [](const auto& a, draco::PointIndex p) {
    std::uint8_t rgb[3] = {0, 0, 0};
    a.ConvertValue(a.mapped_index(p), rgb);
    return Rgb8{rgb[0], rgb[1], rgb[2]};
  });
  out.triangles.reserve(mesh->num_faces());
  for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f) {
    const auto& face = mesh->face(f);
    out.triangles.push_back({face[0].value(), face[1].value(), face[2].value()});
  }
  return out;
}

}  // namespace citymesh
