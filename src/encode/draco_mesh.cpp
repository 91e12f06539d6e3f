// SPDX-License-Identifier: MIT
// The only source that includes Draco.
#include "citymesh/encode/draco_mesh.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>
#include <fmt/format.h>

#include "citymesh/core/error.h"

namespace citymesh {

std::vector<std::uint8_t> draco_encode(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                                       const DracoEncodeParams& params) {
  if (params.position_bits < 1 || params.position_bits > 30 || params.speed < 0 || params.speed > 10) {
    throw ProcessingError(fmt::format("draco: position_bits {} (1..30) or speed {} (0..10) out of range",
                                      params.position_bits, params.speed));
  }
  draco::Mesh mesh;
  mesh.set_num_points(static_cast<std::uint32_t>(positions.size()));
  draco::GeometryAttribute position;
  position.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_FLOAT32, false, sizeof(float) * 3, 0);
  const int id = mesh.AddAttribute(position, true, static_cast<std::uint32_t>(positions.size()));
  for (std::uint32_t i = 0; i < positions.size(); ++i) {
    const float xyz[3] = {positions[i].x, positions[i].y, positions[i].z};
    mesh.attribute(id)->SetAttributeValue(draco::AttributeValueIndex(i), xyz);
  }
  for (const Triangle& t : triangles) {
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
  return {buffer.data(), buffer.data() + buffer.size()};
}

DecodedMesh draco_decode(std::span<const std::uint8_t> data) {
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(data.data()), data.size());
  draco::Decoder decoder;
  auto result = decoder.DecodeMeshFromBuffer(&buffer);
  if (!result.ok()) throw InputError(fmt::format("draco: cannot decode: {}", result.status().error_msg_string()));
  const std::unique_ptr<draco::Mesh> mesh = std::move(result).value();
  const draco::PointAttribute* position = mesh->GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (position == nullptr) throw InputError("draco: the mesh has no POSITION attribute");
  DecodedMesh out;
  out.positions.resize(mesh->num_points());
  for (draco::PointIndex p(0); p < mesh->num_points(); ++p) {
    float xyz[3];
    position->GetMappedValue(p, xyz);
    out.positions[p.value()] = {xyz[0], xyz[1], xyz[2]};
  }
  for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f) {
    const auto& face = mesh->face(f);
    out.triangles.push_back({face[0].value(), face[1].value(), face[2].value()});
  }
  return out;
}

}  // namespace citymesh
