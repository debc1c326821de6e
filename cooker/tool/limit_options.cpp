#include "limit_options.h"

#include <cstring>

#include "lightpatch/cooker/error.h"
#include "lightpatch/cooker/io.h"
#include "lightpatch/planner.h"

namespace lightpatch::tool {

const char* const kInputSizeHelp =
    "  --max-input-mb N       refuse input files (scenes, buffers, images, states, PFM) over N\n"
    "                         MiB (default 1024); only regular files are read\n";

const char* const kImportLimitsHelp =
    "  --max-triangles N      refuse scenes over N triangles, a mesh counted once per node that\n"
    "                         instances it, counted before anything is read (default 4000000)\n"
    "  --max-vertices N       the same for vertices (POSITION elements; default 12000000)\n"
    "  --max-texture-pixels N  refuse base-colour images over N pixels in all, read from\n"
    "                         their headers before decoding (default 33554432: two 4096x4096\n"
    "                         images)\n"
    "  --uri-root DIR         also read buffers and images under DIR (repeatable); by default\n"
    "                         they must lie in the scene's folder or below, links resolved\n";

const char* const kRecomposeLimitsHelp =
    "  --max-lightmap-texels N  refuse packs whose light map has over N texels (default\n"
    "                         16777216, 4096x4096: what the runtime allocates for it)\n"
    "                         (a pack whose authored light map could exceed 1e36 is refused\n"
    "                         too, as the runtime does; no option raises that)\n";

void apply_input_size_option(Args& args) {
  const uint64_t mib = args.count_option(
      cooker::kInputSizeOption, cooker::kDefaultInputSizeLimit >> 20, 1, uint64_t(1) << 24);
  cooker::set_input_size_limit(mib << 20);
}

cooker::ImportLimits parse_import_limits(Args& args) {
  cooker::ImportLimits l;
  constexpr uint64_t kMax = uint64_t(1) << 40;
  l.max_triangles = args.count_option(cooker::kMaxTrianglesOption, l.max_triangles, 1, kMax);
  l.max_vertices = args.count_option(cooker::kMaxVerticesOption, l.max_vertices, 1, kMax);
  l.max_texture_pixels =
      args.count_option(cooker::kMaxTexturePixelsOption, l.max_texture_pixels, 0, kMax);
  std::string root;
  while (args.option(cooker::kUriRootOption, &root)) {
    if (root.empty()) throw ArgsError(std::string(cooker::kUriRootOption) + " needs a folder");
    l.uri_roots.push_back(root);
  }
  return l;
}

RecomposeLimits parse_recompose_limits(Args& args) {
  RecomposeLimits l;
  l.max_lightmap_texels =
      args.count_option("--max-lightmap-texels", l.max_lightmap_texels, 1,
                        uint64_t(pack::kMaxLightmapSize) * pack::kMaxLightmapSize);
  return l;
}

std::string pack_error_text(const Error& error) {
  std::string text = std::string(status_name(error.status)) + ": " + error.message;
  if (error.status == Status::kOverLimit && std::strstr(error.message, "max_lightmap_texels"))
    text += " (--max-lightmap-texels N raises it)";
  if (error.status == Status::kOutOfRange)
    text += " (no option raises it: lower the lights' authored intensities)";
  return text;
}

Status open_pack(const void* data, uint64_t size, const RecomposeLimits& limits, PackView* view,
                 Error* error) {
  const Status s = PackView::open(data, size, limits, view, error);
  return s != Status::kOk ? s : check_authored_map_bound(*view, error);
}

std::string check_cooked_pack(const std::vector<uint8_t>& pack) {
  PackView view;
  Error error;
  const Status s = open_pack(pack.data(), pack.size(), RecomposeLimits(), &view, &error);
  if (s == Status::kOutOfRange)
    throw cooker::CookError("the cooked pack is one the runtime refuses: " +
                            pack_error_text(error));
  if (s != Status::kOverLimit) return {};
  return "the pack is over the runtime's default limits (" + pack_error_text(error) +
         "): verify and recompose refuse it without that option, and a game must raise "
         "RecomposeLimits (pack_view.h)";
}

}  // namespace lightpatch::tool
