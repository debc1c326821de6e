#include "draco_encode.h"

#include <stdexcept>

#include <draco/compression/config/compression_shared.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

namespace lightpatch::scenegen {
namespace {

template <typename Vec>
int add_attribute(draco::Mesh& mesh, draco::GeometryAttribute::Type type,
                  const std::vector<Vec>& values) {
  constexpr int kComponents = Vec::length();
  draco::GeometryAttribute ga;
  ga.Init(type, nullptr, kComponents, draco::DT_FLOAT32, false, sizeof(float) * kComponents, 0);
  const int id = mesh.AddAttribute(ga, true, static_cast<std::uint32_t>(values.size()));
  draco::PointAttribute* attribute = mesh.attribute(id);
  for (std::size_t i = 0; i < values.size(); ++i) {
    float v[kComponents];
    for (int c = 0; c < kComponents; ++c) v[c] = values[i][c];
    attribute->SetAttributeValue(draco::AttributeValueIndex(static_cast<std::uint32_t>(i)), v);
  }
  return static_cast<int>(attribute->unique_id());
}

}  // namespace

DracoPrimitive encode_draco(const Geometry& g, const DracoSettings& settings) {
  draco::Mesh mesh;
  mesh.set_num_points(static_cast<std::uint32_t>(g.vertex_count()));
  for (std::size_t i = 0; i + 2 < g.indices.size(); i += 3) {
    draco::Mesh::Face face;
    for (int k = 0; k < 3; ++k)
      face[k] = draco::PointIndex(g.indices[i + static_cast<std::size_t>(k)]);
    mesh.AddFace(face);
  }
  DracoPrimitive out;
  out.attribute_ids["POSITION"] =
      add_attribute(mesh, draco::GeometryAttribute::POSITION, g.positions);
  out.attribute_ids["NORMAL"] = add_attribute(mesh, draco::GeometryAttribute::NORMAL, g.normals);
  if (!g.uv0.empty())
    out.attribute_ids["TEXCOORD_0"] =
        add_attribute(mesh, draco::GeometryAttribute::TEX_COORD, g.uv0);
  if (!g.uv1.empty())
    out.attribute_ids["TEXCOORD_1"] =
        add_attribute(mesh, draco::GeometryAttribute::TEX_COORD, g.uv1);

  draco::Encoder encoder;
  encoder.SetSpeedOptions(settings.speed, settings.speed);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, settings.position_bits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, settings.normal_bits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, settings.texcoord_bits);
  encoder.SetEncodingMethod(draco::MESH_EDGEBREAKER_ENCODING);
  encoder.SetTrackEncodedProperties(true);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(mesh, &buffer);
  if (!status.ok())
    throw std::runtime_error(std::string("Draco encoding failed: ") + status.error_msg());
  out.bytes.assign(buffer.data(), buffer.data() + buffer.size());
  out.point_count = encoder.num_encoded_points();
  out.face_count = encoder.num_encoded_faces();
  return out;
}

}  // namespace lightpatch::scenegen
