// The options of every verb that cooks (cook, bake-state, plan): the scene, the output, the
// layout and bake options, the report and quiet flags (DESIGN.md, Command line).
#pragma once

#include <string>

#include "args.h"
#include "lightpatch/cooker/bake.h"
#include "lightpatch/cooker/import.h"
#include "lightpatch/cooker/layout.h"

namespace lightpatch::tool {

struct CookOptions {
  std::string scene_path;
  std::string output;
  std::string report_path;
  cooker::LayoutOptions layout;
  cooker::BakeOptions bake;
  cooker::ImportLimits import;
  bool quiet = false;
};

// Parses -o (named `output_what` in errors) and the cook's options. Options first: a positional
// is any item not starting with '-', which an option's value could be. cook_verbs.cpp.
CookOptions parse_cook_options(Args& args, const char* output_what);

// Fails early, before a long cook, when the output's folder cannot take a file.
void probe_output_folder(const std::string& path);

}  // namespace lightpatch::tool
