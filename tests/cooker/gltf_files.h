// glTF files for the import, CLI and Draco tests: small scenes written with scenegen, a scratch
// folder per test, and the means to edit a valid file into a hostile one (its JSON, its binary
// data, its .glb container).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lightpatch/scenegen/scene_builder.h"

namespace lightpatch::test {

// A fresh folder named after the running test, removed when the object goes out of scope.
class ScratchDir {
 public:
  ScratchDir();
  ~ScratchDir();
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  // Names of the entries in the folder, sorted (to check that nothing was left behind).
  std::vector<std::string> entries() const;

 private:
  std::filesystem::path path_;
};

std::vector<std::uint8_t> read_bytes(const std::string& path);
void write_bytes(const std::string& path, const std::vector<std::uint8_t>& bytes);
void write_text(const std::string& path, const std::string& text);

// A glTF document split into its JSON and its one binary buffer (the .glb BIN chunk or .bin file).
struct GltfParts {
  nlohmann::ordered_json json;
  std::vector<std::uint8_t> bin;
};

GltfParts parts_of(const scenegen::SceneBuilder& builder,
                   const scenegen::WriteOptions& options = {});
GltfParts split_glb(const std::vector<std::uint8_t>& glb);
std::vector<std::uint8_t> join_glb(const GltfParts& parts);
// Writes `parts` as `stem`.gltf with the buffer in `stem`.bin beside it; returns the .gltf path.
std::string write_gltf(const ScratchDir& dir, const std::string& stem, GltfParts parts);
// Writes `parts` as `stem`.glb; returns its path.
std::string write_glb(const ScratchDir& dir, const std::string& stem, const GltfParts& parts);

// Byte offset in the buffer of component `component` of element `element` of float accessor
// `accessor` (tightly packed or strided views).
std::size_t float_offset(const GltfParts& parts, int accessor, std::size_t element, int component);
void set_float(GltfParts& parts, int accessor, std::size_t element, int component, float value);
float get_float(const GltfParts& parts, int accessor, std::size_t element, int component);
// Overwrites index `element` of an unsigned index accessor (uint16 or uint32).
void set_index(GltfParts& parts, int accessor, std::size_t element, std::uint32_t value);

std::string base64(const std::vector<std::uint8_t>& data);
// An 8-bit RGB PNG of w x h pixels, `rgb` row by row from the top.
std::vector<std::uint8_t> png(int w, int h, const std::vector<std::uint8_t>& rgb);

// A small scene that exercises everything the cooks need (a few hundred triangles):
// a 4 m x 4 m floor ("floor"), a static box ("pillar"), a semi-dynamic box ("crate") on the
// floor, a semi-dynamic point light ("lamp", radius 0 or `lamp_radius`) and a static spot light
// ("spot") aimed at the floor. Light-map UVs are left to the cooker's unwrap.
scenegen::SceneBuilder small_room(float lamp_radius = 0.0f);

// The same room with light-map UVs (TEXCOORD_1) of its own: every face a cell of a 4 x 4 grid in
// [0,1]^2, so the cooker uses them verbatim and the layout does not depend on vertex order.
scenegen::SceneBuilder small_room_with_uv1();

// Bounce light beside a thin object (issue 11's third accuracy scene): a closed 4 x 2.5 x 4 m room
// ("room", inward-facing plaster, albedo 0.7), a 2 cm thick wooden panel ("panel", semi-dynamic,
// 1.2 m wide, 1.3 m tall) standing 5 cm in front of the +X wall, a semi-dynamic point lamp
// ("lamp", 8 cd, radius 5 cm) that lights that wall and the panel's face obliquely, and a static
// spot ("spot", 60 cd) aimed straight down whose cone reaches only the floor, so with the lamp
// off every wall is lit by bounce light alone. Big quads (two triangles a face); light-map UVs
// are left to the cooker's unwrap.
scenegen::SceneBuilder thin_panel_room();

// A face just above a partly lit floor (the small inn's worst texels: faces a few centimetres
// from a candle's lit surroundings): the same closed room, a static wooden slab ("slab", 60 x 60 x
// 3.5 cm) hovering 1.5 cm above the floor, and a semi-dynamic candle ("candle", a point light of
// 2 cd, radius 1 cm) 12 cm beside the slab and 8 cm above the floor. The floor is lit up to the
// slab's edge and a few centimetres under it, and dark beyond; the slab's underside sees only that
// floor, from 1.5 cm, so where its gather rays land decides its light. Big quads; light-map UVs
// are left to the cooker's unwrap.
scenegen::SceneBuilder low_slab_room();

// A moving light between two rooms (issue 16's test scene): two closed plaster rooms of 3.9 x 2.5 x
// 4 m side by side along X (room A x < -0.1, room B x > 0.1), 10 cm slabs each their own node, a
// 20 cm partition with a 1 x 2 m doorway at z in [1, 2], a red rug in room A ("rug"), a static
// lamp in room B ("lamp_b", 6 cd, radius 5 cm) and a moving lantern ("lantern", extras "moving":
// true, 3 cd, radius 4 cm) at (-2, 1.2, -1) in room A. Big quads (boxes); light-map UVs left to
// the cooker's unwrap.
scenegen::SceneBuilder two_rooms_lantern();

}  // namespace lightpatch::test
